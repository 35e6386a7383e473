"""Scenes: TOML data (``schema``), input signals (``signals``), the fmpy runner
(``runner``), plots (``plot``) and the independent reference paths (``references``)."""

from .schema import Case, Reference, ScenarioError, Scene, discover, load

__all__ = ["Case", "Reference", "ScenarioError", "Scene", "discover", "load"]
