"""Reports of a run: the content is built once as a :class:`~pipeline.report.document.Document`
and rendered to self-contained HTML (:mod:`~pipeline.report.html`) and A4 PDF
(:mod:`~pipeline.report.pdf`) with the same figures (:mod:`~pipeline.report.plots`)."""
