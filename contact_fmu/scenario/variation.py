"""A scene with some of its values replaced: the runs of a parameter study.

A varied name (``schema.check_varied``) is an FMU parameter, an input (then held
constant at the value) or a number field of one piece of an input's signal,
"INPUT.piece.field" (e.g. ``My_ex.sine.amplitude``). The value replaces the scene's
in [parameters] or [inputs] and in every case that sets its own: a varied value holds
for every case. The result is checked as any scene, and it keeps the base scene's model
configuration, so every run uses the base scene's FMU (the values are start values and
inputs, not a new model).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Mapping
from typing import Any

from ..fmu import variables as fv
from .schema import Scene, _piece_specs, check_varied, from_data


def _set(table: dict[str, Any], name: str, value: float, is_input: bool) -> None:
    if is_input and "." in name:
        inp, kind, key = name.split(".")
        if inp not in table:
            return
        spec = copy.deepcopy(table[inp])
        for piece in _piece_specs(spec):
            if isinstance(piece, dict) and kind in piece:
                piece[kind][key] = value
        table[inp] = spec
    elif name in table or not is_input:
        table[name] = value


def check(scene: Scene, names: list[str]) -> None:
    """Every name can be varied in ``scene`` (ScenarioError naming it otherwise)."""
    for name in names:
        check_varied(scene.path, name, scene.config, scene.source)


def apply(scene: Scene, values: Mapping[str, float]) -> Scene:
    """``scene`` with ``values`` (varied name -> number) in place of its own: checked as a
    scene (ScenarioError naming a value it rejects), with the base scene's FMU."""
    raw = copy.deepcopy(scene.source)
    raw.pop("reference", None)  # a varied run has no stored reference
    raw.pop("sweep", None)
    for name, value in values.items():
        is_input = name.split(".")[0] in scene.config.inputs
        var = fv.BY_NAME.get(name)
        if var is not None and var.type == "Integer" and float(value).is_integer():
            value = int(value)  # a study's values are floats; the scene's type is integer
        section = "inputs" if is_input else "parameters"
        raw.setdefault(section, {})
        if is_input and "." not in name:
            raw[section][name] = value
        else:
            _set(raw[section], name, value, is_input)
        for case in raw.get("cases", []):
            own = case.get(section)
            if own is not None:
                if is_input:
                    _set(own, name, value, True)
                else:
                    own.pop(name, None)  # the varied value holds for every case
    varied = from_data(scene.path, raw)
    return dataclasses.replace(varied, config=scene.config, sweep=scene.sweep)
