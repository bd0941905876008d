"""``rczone validate``: run reference cases (filled in by the VDI 6007 work)."""
