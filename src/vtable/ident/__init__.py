"""Identification from measured channels."""

from vtable.ident.tf import TransferFunction, transfer_function

__all__ = ["TransferFunction", "transfer_function"]
