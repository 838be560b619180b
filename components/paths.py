"""Where the shipped data lives: the ``models/`` folder of the source tree (editable install)."""

from __future__ import annotations

from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parent.parent / "models"
DEFAULT_TABLE = MODELS_DIR / "friction_table.npz"
