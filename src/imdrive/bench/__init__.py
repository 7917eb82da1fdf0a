"""The estimator bench: every speed estimator and R2 adaptation method on the same
plant, the same test protocol and the same metrics (``imdrive bench-estimators``).

:mod:`.protocol` says what is run, :mod:`.metrics` what is measured (from each run's log),
:mod:`.report` runs it all on the batch engine and writes the table, figures and Markdown.
"""
