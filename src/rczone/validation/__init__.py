"""Validation against independent references: the VDI 6007-1 test cases (:mod:`rczone.validation.vdi6007`)."""
