"""Study reports: self-contained HTML pages with results.json, written atomically, and their index."""

from .animation import Animation, parse_case
from .content import (
    Column,
    Comparison,
    MechanismInfo,
    Parameter,
    Section,
    StudyResult,
)
from .render import render_index, render_report
from .study import STUDY_PACKAGE, Study, StudyContext, compute_animation, find_study, run_study, study_names
from .writer import output_folder, write_index, write_report

__all__ = [
    "STUDY_PACKAGE",
    "Animation",
    "Column",
    "Comparison",
    "MechanismInfo",
    "Parameter",
    "Section",
    "Study",
    "StudyContext",
    "StudyResult",
    "compute_animation",
    "find_study",
    "output_folder",
    "parse_case",
    "render_index",
    "render_report",
    "run_study",
    "study_names",
    "write_index",
    "write_report",
]
