"""``python -m pound_mc.study [--check] [FOLDER]``: rewrite (or check) the schema reference.

Writes ``SCHEMA.md`` and ``pound-mc.schema.json`` into FOLDER (default ``studies``) from the
declared tables (:mod:`pound_mc.study.schema`).
"""

import sys

from pound_mc.study.schema import main

sys.exit(main())
