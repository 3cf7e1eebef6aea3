"""Figures and summaries of runs."""

from tetherland.report.figures import figure_6_5, figure_path, nominal_series, save_figures

__all__ = ["figure_6_5", "figure_path", "nominal_series", "save_figures"]
