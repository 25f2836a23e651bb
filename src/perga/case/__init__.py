"""Case files: the schema (units, ranges) and loading with every problem reported at once."""

from perga.case.load import CaseError, load_case
from perga.case.schema import Case

__all__ = ["Case", "CaseError", "load_case"]
