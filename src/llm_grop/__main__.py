"""``python -m llm_grop``: the ``llm-grop`` command."""

import sys

from llm_grop.entry import main

if __name__ == "__main__":
    sys.exit(main())
