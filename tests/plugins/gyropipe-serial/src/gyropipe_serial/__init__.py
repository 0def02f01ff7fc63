"""A gyropipe plugin adding the batch executor ``serial`` (tests/plugins/test_executor_plugin.py)."""
