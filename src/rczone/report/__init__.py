"""Reports: self-contained HTML pages, figures and JSON results written atomically."""

from rczone.report.html import Report
from rczone.report.io import write_json_atomic, write_text_atomic

__all__ = ["Report", "write_json_atomic", "write_text_atomic"]
