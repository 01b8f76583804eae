"""The truth simulator's one error type (a one-line message naming what was wrong)."""


class TruthError(ValueError):
    """Bad input to the truth simulator."""
