import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
# tests/ holds helper modules (independent reference solutions) imported by name
sys.path.insert(0, str(Path(__file__).parent))
os.environ.setdefault("MPLBACKEND", "Agg")
