"""Sample recordings and demonstrations shipped inside the package.

``sample-reach-{1,2,3}.tape.csv`` are 3.5 s of the simulated operator reaching the default goal of
:class:`studio.learning.ArmGrid`, each with the demonstration cut from its reach
(``sample-reach-N.demo.json``). Every data folder offers them read-only, so a new user can play,
train on and copy them at once. ``python recordings/make_samples.py`` regenerates them byte for
byte (fixed seeds and creation time).
"""

from __future__ import annotations

from pathlib import Path

SAMPLES_DIR = Path(__file__).resolve().parent
"""The folder holding the shipped ``sample-*.tape.csv`` and ``sample-*.demo.json`` files."""
