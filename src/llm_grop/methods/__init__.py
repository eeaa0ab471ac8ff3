"""The compared methods (paper §IV): TPRA, LATP, GROP and LLM-GROP, behind one protocol."""
