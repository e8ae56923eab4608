"""The ``rasterhw`` command line."""
