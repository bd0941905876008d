"""The paper's study reproduced on the built-in virtual building (sections III and IV).

:mod:`~rczone.study.paper` computes it and returns plain results; its page layout is
:mod:`rczone.report.demo` (``rczone demo``).
"""

from rczone.study.paper import (
    PAPER_FREE,
    ClosedLoopStudy,
    IdentificationStudy,
    ModelOrderStudy,
    PaperStudy,
    run_paper_study,
    true_equivalent,
)

__all__ = [
    "PAPER_FREE",
    "ClosedLoopStudy",
    "IdentificationStudy",
    "ModelOrderStudy",
    "PaperStudy",
    "run_paper_study",
    "true_equivalent",
]
