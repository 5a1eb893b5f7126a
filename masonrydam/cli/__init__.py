"""Command-line interface (``masonrydam``)."""
