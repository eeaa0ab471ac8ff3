"""The JSON contract, the wire formats other programs read: the documents as typed models
(:mod:`~llm_grop.contract.models`), the arrangement JSON (:mod:`~llm_grop.contract.serialize`),
the run JSON (:mod:`~llm_grop.contract.run_json`), the plan JSON
(:mod:`~llm_grop.contract.plan_doc`) and their JSON Schemas
(:mod:`~llm_grop.contract.schemas`). Built from the records of :mod:`llm_grop.world`."""
