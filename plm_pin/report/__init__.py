"""Study reports: self-contained HTML pages with results.json, written atomically, and their index."""

from .animation import Animation
from .content import (
    Column,
    Comparison,
    MechanismInfo,
    Parameter,
    Section,
    StudyResult,
)
from .study import Study, StudyCase, StudyContext, find_study, run_study, study_modules, study_names
from .writer import write_index, write_report

__all__ = [
    "Animation",
    "Column",
    "Comparison",
    "MechanismInfo",
    "Parameter",
    "Section",
    "Study",
    "StudyCase",
    "StudyContext",
    "StudyResult",
    "find_study",
    "run_study",
    "study_modules",
    "study_names",
    "write_index",
    "write_report",
]
