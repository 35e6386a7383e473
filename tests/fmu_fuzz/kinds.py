"""The kinds of FMU the project builds, as the fuzzer drives them.

Each kind is a model configuration (a scene's, or the full FMU of a mode) built once
with ``fmu_build`` (cached by content under out/fmu), its variables read back from the
built model description, and the nominal values a run starts from. The admissibility
of a value is the model's declared range (``ModelConfig.check``, the table of
contact_fmu/fmu/variables.py that the model description's min/max come from).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import fmpy

import fmu_build
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "out" / "fmu"


@dataclass(frozen=True)
class Kind:
    """One kind of FMU: ``config()`` gives its ModelConfig; ``nominal`` replaces start
    values in every run (a small transient grid keeps a step cheap); ``slow``: a doStep
    runs in Python at a cost per internal step, so long steps are drawn rarely."""

    name: str
    scene: str | None = None
    full: str | None = None
    nominal: dict[str, Any] = field(default_factory=dict)
    slow: bool = False

    def config(self) -> ModelConfig:
        if self.scene is not None:
            return load(ROOT / "scenarios" / f"{self.scene}.toml").config
        return ModelConfig.full(self.full)

    @cached_property
    def cfg(self) -> ModelConfig:
        return self.config()

    @cached_property
    def path(self) -> Path:
        return fmu_build.build(self.cfg, OUT).path

    @cached_property
    def variables(self) -> dict[str, Any]:
        """name -> fmpy's ScalarVariable of the built FMU."""
        md = fmpy.read_model_description(str(self.path))
        return {v.name: v for v in md.modelVariables}

    @property
    def mode(self) -> str:
        return self.cfg.mode

    def names(self, causality: str, type_: str | None = None) -> list[str]:
        return [
            n
            for n, v in self.variables.items()
            if v.causality == causality and (type_ is None or v.type == type_)
        ]

    def start(self, name: str) -> Any:
        """The value a run starts from: the kind's nominal one, else the FMU's start."""
        if name in self.nominal:
            return self.nominal[name]
        v = self.variables[name]
        if v.type == "Real":
            return float(v.start)
        if v.type == "Integer":
            return int(v.start)
        return v.start or ""

    def admissible(self, name: str, value: Any) -> bool:
        """Whether ``value`` is in the declared range of ``name`` (a NaN or inf never)."""
        if isinstance(value, float) and not math.isfinite(value):
            return False
        return self.cfg.check(name, value) is None


KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        Kind("fig13", scene="fig13"),
        Kind("full_body", full="body", slow=True),
        Kind("full_contact", full="contact"),
        Kind("rail_creep", scene="rail_creep"),
        Kind("full_rigid_body", full="rigid_body"),
        Kind("cornering", scene="cornering", slow=True),
        Kind("fig12_transient", scene="fig12_transient", nominal={"nx": 8, "ny": 4}, slow=True),
        Kind("rail_traction", scene="rail_traction"),
    )
}
