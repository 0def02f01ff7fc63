"""Batch processing: many wells, one DAG run each, on a process pool or a Dask cluster,
recorded in an SQLite run ledger (see :mod:`pipeline.batch.run`)."""
