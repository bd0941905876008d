"""Independent reference cases rczone is checked against: the VDI 6007-1 test cases (:mod:`rczone.reference.vdi6007`)."""
