"""The paper's experiment (§IV): trials, the bench runner, the summary and the plots.

It sits above the public API: a trial runs :func:`llm_grop.api.run` and rates the final
table with the automatic rater (:mod:`llm_grop.evaluation`).
"""
