"""The human rating study of a bench's pictures (paper §IV, "Rating Criteria").

:mod:`~llm_grop.ratings.study` makes a study database from a bench directory and invites
raters; :mod:`~llm_grop.ratings.app` is the website they rate on (FastAPI, the ``ratings``
extra); :mod:`~llm_grop.ratings.report` turns their ratings into the paper's figures.
Only the command line imports it; it reads bench results and never runs a pipeline.
"""
