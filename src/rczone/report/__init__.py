"""Reports: self-contained HTML pages and figures (results files: :mod:`rczone.files.atomic`)."""

from rczone.report.html import Report

__all__ = ["Report"]
