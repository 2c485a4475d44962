"""The one exception of mill_bag."""

from __future__ import annotations


class BagError(ValueError):
    """A bag that cannot be written or read as asked; str() says why in one line."""
