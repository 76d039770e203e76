"""``python -m pound_mc`` runs the command line."""

import sys

from pound_mc.cli import main

sys.exit(main())
