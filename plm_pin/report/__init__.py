"""Study reports: self-contained HTML pages with results.json, written atomically, and their index."""

from .content import (
    Column,
    Comparison,
    MechanismInfo,
    Parameter,
    Section,
    StudyResult,
)
from .render import render_index, render_report
from .study import STUDY_PACKAGE, Study, StudyContext, find_study, run_study, study_names
from .writer import output_folder, write_index, write_report

__all__ = [
    "STUDY_PACKAGE",
    "Column",
    "Comparison",
    "MechanismInfo",
    "Parameter",
    "Section",
    "Study",
    "StudyContext",
    "StudyResult",
    "find_study",
    "output_folder",
    "render_index",
    "render_report",
    "run_study",
    "study_names",
    "write_index",
    "write_report",
]
