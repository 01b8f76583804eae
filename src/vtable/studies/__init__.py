"""Interaction studies: response spectra (report ch. 9)."""

from vtable.studies.spectra import Spectrum, response_spectrum

__all__ = ["Spectrum", "response_spectrum"]
