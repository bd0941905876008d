"""The ``rczone`` command-line interface."""
