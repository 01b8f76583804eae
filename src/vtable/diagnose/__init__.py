"""Comparing models with measured campaigns and diagnosing the missing physics."""

from vtable.diagnose.compare import Comparison, compare, localisation_text, noise_floor
from vtable.diagnose.engine import Diagnoser, Diagnosis, diagnose

__all__ = ["Comparison", "Diagnoser", "Diagnosis", "compare", "diagnose", "localisation_text",
           "noise_floor"]
