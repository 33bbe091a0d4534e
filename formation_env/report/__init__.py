"""The validation report (``formation-env report``): the project's numbers beside the thesis's,
markdown with PNG figures. See :mod:`formation_env.report.builder`."""

from .builder import SECTIONS, build_report

__all__ = ["SECTIONS", "build_report"]
