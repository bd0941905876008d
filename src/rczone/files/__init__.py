"""Files a user hands in and files rczone writes.

:mod:`~rczone.files.text` reads untrusted text files (size and name limits, regular files only,
one-line errors); :mod:`~rczone.files.atomic` writes results atomically, inside the output
folder only (no symlink followed), all or nothing.
"""
