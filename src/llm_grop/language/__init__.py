"""Reading people's words (below arrangement and evaluation, which both read through it).

* :mod:`~llm_grop.language.vocabulary`: the one vocabulary of relation phrases and request
  words, in ``vocabulary.yaml`` and ``request_words.yaml``;
* :mod:`~llm_grop.language.matcher` and :mod:`~llm_grop.language.request`: the catalog
  matcher, the fast path of reading a request;
* :mod:`~llm_grop.language.reading`: the typed reading and the request it makes;
* :mod:`~llm_grop.language.llm_reading` and :mod:`~llm_grop.language.understanding`: the
  LLM's reading of a whole request, and the choice between the two;
* :mod:`~llm_grop.language.answer_tokens` and :mod:`~llm_grop.language.answer_reader`: the
  reader of relations in free text (the LLM's Template 1 answers and preferences);
* :mod:`~llm_grop.language.distance`: the reader of distances in free text.
"""
