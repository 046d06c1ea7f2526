"""The verification report of a reduction, from its summary dict alone (no compiled kryflex code, no PETSc):
summary.py builds the dict from a reducer's results; writer.py writes summary.json, report.md and the plots."""
from .schema import ReportError, validate_summary
from .writer import begin_report, write_report, write_unverified

__all__ = ["ReportError", "begin_report", "validate_summary", "write_report", "write_unverified"]
