"""Files users write or the package ships, read into the records of :mod:`llm_grop.world`:
dining-room scenes (:mod:`~llm_grop.files.scene_file`), the feasibility profiles
(:mod:`~llm_grop.files.profiles`); and how llm-grop writes JSON and other files
(:mod:`~llm_grop.files.jsonio`)."""
