"""Rolling/sliding contact of an elastic body on an elastic substrate (Spector & Batra 1995)."""

from ._validate import InputError
from .layer import LayerContact, TractionField

__all__ = ["InputError", "LayerContact", "TractionField"]
