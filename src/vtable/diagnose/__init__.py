"""Comparing models with measured campaigns and diagnosing the missing physics."""

from vtable.diagnose.compare import Comparison, compare, noise_floor
from vtable.diagnose.engine import Diagnoser, diagnose
from vtable.diagnose.prose import localisation_text
from vtable.diagnose.result import Diagnosis, DiagnosisInterrupted, ModelComparison

__all__ = ["Comparison", "Diagnoser", "Diagnosis", "DiagnosisInterrupted", "ModelComparison",
           "compare", "diagnose", "localisation_text", "noise_floor"]
