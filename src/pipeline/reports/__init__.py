"""Reports of a run: the content is built once as a :class:`~pipeline.reports.document.Document`
and rendered to self-contained HTML (:mod:`~pipeline.reports.html`) and A4 PDF
(:mod:`~pipeline.reports.pdf`) with the same figures (:mod:`~pipeline.reports.plots`)."""
