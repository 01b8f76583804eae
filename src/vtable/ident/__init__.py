"""Identification from measured channels."""

from vtable.ident.tf import TransferFunction, transfer_function, transfer_function_via

__all__ = ["TransferFunction", "transfer_function", "transfer_function_via"]
