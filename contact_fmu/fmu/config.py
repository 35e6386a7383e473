"""Which model a built FMU holds: mode, contact law, stepper, lateral parts, variables.

A ``ModelConfig`` is plain data (JSON through ``to_dict``/``from_dict``): the build
writes it into the generated FMU script, and the adapter reads it back. Values that
later issues add to the scene schema are listed in ``PLANNED`` and refused here with a
clear error until implemented.

``phase = "transient"``: the body-mode FMU carries the traction field of the
thin-layer law as its state (``thin_layer_field.TransientRollingBody``) instead of the steady
creep law; its grid and step are parameters (nx, ny, cells_per_step), and it can write
the field to a file at chosen times (field_file, field_times). The steady methods and
schemes do not apply to it, and the transient half-space field is not offered in an
FMU (see ``TRANSIENT_HALFSPACE``).

The half-space law (``contact_law = "halfspace"``) carries its declaration in
``law_spec`` (``halfspace.spec.TableSpec`` as plain data: materials, radii, layers, the
table's range and resolution). Its geometry and materials are structural: they are not
FMU parameters (the layer law's Ry, k1, k2, kb, ks do not exist in such an FMU), the
rolling radius Rx is a parameter fixed to the table's body radius (``fixed``: any other
value is refused), and mu stays free (the normalised table does not depend on it).
"""

from __future__ import annotations

import importlib
from dataclasses import asdict, dataclass, field
from functools import cached_property
from typing import Any

from .._validate import InputError
from . import variables as fv

# Implemented choices, and the module that implements each (relative to the package).
MODEL_MODULES = {
    "body": "fmu.body_model",
    "contact": "fmu.contact_model",
    "rigid_body": "fmu.rigid_body",
}
# The body model of phase "transient" (body mode, thin-layer field).
TRANSIENT_MODULE = "fmu.body_transient"
LAW_MODULES = {"layer": "laws.thin_layer", "halfspace": "halfspace.spec"}
# Data files a law reads at run time (paths relative to the package, e.g. a table .npz):
# the build copies them next to the law's module in the FMU's resources.
LAW_DATA: dict[str, tuple[str, ...]] = {"layer": (), "halfspace": ()}
# Data files the build generates for a law from ``law_spec`` (path relative to the
# package): the half-space law's creep-force table, built by the numerics layer.
GENERATED_DATA: dict[str, str] = {"halfspace": "halfspace/creep_table.npz"}
PHASES = ("steady", "transient")
METHODS = ("full", "quasistationary")
# Time-stepping schemes of the body-mode stepper (``integrator.SCHEMES``; a test keeps the
# two equal: importing the integrator here would put it into every FMU, contact mode too).
SCHEMES = ("lobatto3c", "sdirk2")
# Recognised scene values that later issues implement.
PLANNED: dict[str, tuple[str, ...]] = {}
# Why phase = "transient" is refused with the half-space law (measured in
# docs/halfspace.md, "Transient rolling"): each step of Kalker's transient solves two to
# three contact problems with the influence coefficients (the body's slip iteration),
# 1 to 6 s of computing per contact length rolled on 16 x 16 to 32 x 32 elements; a
# railway scene of 0.1 s at 30 m/s rolls about 200 contact lengths, 4 to 20 minutes per
# case, for transients that last 2 to 10 contact lengths.
TRANSIENT_HALFSPACE = (
    '"layer" with phase = "transient": the transient half-space field costs 1 to 6 s of '
    "computing per contact length rolled (a railway scene of 0.1 s at 30 m/s rolls "
    'about 200 of them); use phase = "steady" with the half-space law, or '
    "contact_fmu.halfspace.transient.TransientHalfSpaceBody outside an FMU"
)

VY_MODES = ("zero", "ratio", "eq10")
SPIN_MODES = ("zero", "ratio", "eq11")


def _choice(name: str, value: object, allowed: tuple[str, ...]) -> str:
    if value in allowed:
        return str(value)
    planned = PLANNED.get(name, ())
    if value in planned:
        raise InputError(name, value, f"one of {allowed}: {value!r} is not implemented yet")
    raise InputError(name, value, f"one of {allowed}")


@dataclass(frozen=True)
class ModelConfig:
    """The structure of one FMU.

    ``methods``: the steppers the FMU offers (body mode); with more than one, the
    string parameter ``method`` chooses. ``schemes``: the integrator schemes it offers
    (body mode); with more than one, the string parameter ``scheme`` chooses (the first
    is the default). ``law_spec``: the contact law's structural data (the half-space
    law's TableSpec as plain data; empty for the layer law). ``vy``/``spin``: how Vy and
    Omega_z follow
    (body mode): "zero" (held at 0, no lateral variables), "ratio" (held ratio to Vx,
    parameters vy_ratio/spin_ratio) or Eqs. (10)/(11). ``starts``: start values that
    replace the declared defaults. ``experiment``: (start, stop, step) in s, or None.
    """

    name: str
    mode: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    contact_law: str = "layer"
    phase: str = "steady"
    methods: tuple[str, ...] = ("full",)
    schemes: tuple[str, ...] = ("lobatto3c",)
    vy: str = "zero"
    spin: str = "zero"
    starts: dict[str, Any] = field(default_factory=dict)
    experiment: tuple[float, float, float] | None = None
    description: str = ""
    law_spec: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise InputError("name", self.name, "a Python identifier (letters, digits, _)")
        _choice("mode", self.mode, tuple(MODEL_MODULES))
        _choice("contact_law", self.contact_law, tuple(LAW_MODULES))
        if self.has_table:  # checked and normalised (radii inf -> "inf", loads sorted)
            object.__setattr__(self, "law_spec", self.table_spec.to_dict())
        elif self.law_spec:
            raise InputError(
                "halfspace", self.law_spec, 'given only with contact_law = "halfspace"'
            )
        _choice("phase", self.phase, PHASES)
        if self.transient:
            if self.mode != "body":
                raise InputError(
                    "phase", self.phase, "used in body mode (the field is the body's state)"
                )
            if self.contact_law != "layer":
                raise InputError("contact_law", self.contact_law, TRANSIENT_HALFSPACE)
            if tuple(self.methods) != ("full",):
                raise InputError(
                    "method",
                    list(self.methods),
                    'left out with phase = "transient" (the steady methods do not apply)',
                )
            if tuple(self.schemes) != SCHEMES[:1]:
                raise InputError(
                    "scheme",
                    list(self.schemes),
                    'left out with phase = "transient" (its field and body share one '
                    "L-stable SDIRK2 step)",
                )
        if not self.methods:
            raise InputError("method", self.methods, f"at least one of {METHODS}")
        for m in self.methods:
            _choice("method", m, METHODS)
        if not self.schemes:
            raise InputError("scheme", self.schemes, f"at least one of {SCHEMES}")
        for m in self.schemes:
            _choice("scheme", m, SCHEMES)
        _choice("vy", self.vy, VY_MODES)
        _choice("spin", self.spin, SPIN_MODES)
        if self.mode != "body" and (self.vy, self.spin, self.methods, self.schemes) != (
            "zero",
            "zero",
            ("full",),
            SCHEMES[:1],
        ):
            raise InputError("mode", self.mode, 'body for lateral parts, "method" and "scheme"')
        self._check_names("input", self.inputs, fv.INPUT)
        self._check_names("output", self.outputs, fv.OUTPUT)
        required = {"body": ("P",), "contact": ("P", "Vx", "Omega_y"), "rigid_body": ("Tx",)}
        for name in required[self.mode]:
            if name not in self.inputs:
                raise InputError(
                    "inputs", list(self.inputs), f"to include {name} in {self.mode} mode"
                )
        for name, value in self.starts.items():
            var = fv.BY_NAME.get(name)
            if var is None or not fv.applicable(var, self):
                why = f"a variable of this {self.mode}-mode model"
                if var is not None and var.laws and self.contact_law not in var.laws:
                    why += f" (a {self.contact_law} model takes its contact from [halfspace])"
                raise InputError(name, value, why)
            problem = self.check(name, value)
            if problem is not None:
                raise InputError(name, value, problem)
        if "method" in self.starts and self.starts["method"] not in self.methods:
            raise InputError("method", self.starts["method"], f"one of {self.methods}")
        if "scheme" in self.starts and self.starts["scheme"] not in self.schemes:
            raise InputError("scheme", self.starts["scheme"], f"one of {self.schemes}")

    def _check_names(self, what: str, names: tuple[str, ...], causality: str) -> None:
        allowed = fv.available(self, causality)
        for n in names:
            if n not in allowed:
                raise InputError(f"{what}s", n, f"one of {allowed} in this {self.mode}-mode model")
        if len(set(names)) != len(names):
            raise InputError(f"{what}s", list(names), "without repetitions")

    # ---- derived ---------------------------------------------------------------------
    @property
    def variables(self) -> list[fv.Var]:
        """The FMU's variables in value-reference order."""
        return fv.select(self, self.inputs, self.outputs)

    def start(self, var: fv.Var) -> Any:
        """Start value of ``var``: the configured one, else the declared default (the
        table's values for a half-space FMU's Rx and mu)."""
        if var.name == "method":
            return self.starts.get("method", self.methods[0])
        if var.name == "scheme":
            return self.starts.get("scheme", self.schemes[0])
        if var.name in self.fixed:
            return self.fixed[var.name]
        if var.name == "mu" and self.has_table:
            return self.starts.get("mu", self.table_spec.mu)
        return self.starts.get(var.name, var.start)

    @property
    def transient(self) -> bool:
        """Whether the FMU carries the traction field as state (phase "transient")."""
        return self.phase == "transient"

    # ---- the half-space law's table --------------------------------------------------
    @property
    def has_table(self) -> bool:
        """Whether the model's contact law is the tabulated half-space law."""
        return self.contact_law == "halfspace" and self.mode != "rigid_body"

    @cached_property
    def table_spec(self) -> Any:
        """``halfspace.spec.TableSpec`` of ``law_spec`` (imported lazily: only an FMU with
        that law carries the module)."""
        spec = importlib.import_module(f"..{LAW_MODULES['halfspace']}", __package__)
        return spec.TableSpec.from_dict(self.law_spec)

    @property
    def fixed(self) -> dict[str, float]:
        """Parameters whose value the build fixes: a half-space FMU's rolling radius Rx
        is the body radius its table was built for."""
        return {"Rx": self.table_spec.Rx} if self.has_table else {}

    def check(self, name: str, value: object) -> str | None:
        """None if ``value`` is admissible for the variable ``name`` of this model, else
        the requirement it violates (the declared range, or the fixed value)."""
        problem = fv.BY_NAME[name].check(value)
        fixed = self.fixed.get(name)
        if problem is None and fixed is not None and float(value) != fixed:  # type: ignore[arg-type]
            return (
                f"{fixed!r}, the value this FMU's creep-force table was built for (a "
                "structural value: change the scene's [halfspace] table and rebuild)"
            )
        return problem

    def bounds(self, var: fv.Var) -> tuple[float | None, float | None]:
        """(min, max) of ``var`` in the model description: min = max for fixed values,
        none for an output (``Var.bounds``)."""
        if var.name in self.fixed:
            return self.fixed[var.name], self.fixed[var.name]
        return var.bounds(self.mode)

    @property
    def model_module(self) -> str:
        """The model's module; phase "transient" has its own, so that only its FMUs carry
        the transient field."""
        return TRANSIENT_MODULE if self.transient else MODEL_MODULES[self.mode]

    @property
    def law_module(self) -> str | None:
        return LAW_MODULES[self.contact_law] if self.mode != "rigid_body" else None

    @property
    def data_files(self) -> tuple[str, ...]:
        """Package-relative data files the FMU must carry (the law's tables)."""
        return LAW_DATA.get(self.contact_law, ()) if self.mode != "rigid_body" else ()

    @property
    def generated_files(self) -> tuple[str, ...]:
        """Package-relative data files the build generates for the FMU (from law_spec)."""
        return (GENERATED_DATA[self.contact_law],) if self.has_table else ()

    # ---- plain data --------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        for k in ("inputs", "outputs", "methods", "schemes"):
            d[k] = list(d[k])
        d["experiment"] = list(self.experiment) if self.experiment else None
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ModelConfig:
        d = dict(d)
        for k in ("inputs", "outputs", "methods", "schemes"):
            d[k] = tuple(d[k])
        if d.get("experiment") is not None:
            d["experiment"] = tuple(float(x) for x in d["experiment"])
        return cls(**d)

    @classmethod
    def full(cls, mode: str) -> ModelConfig:
        """The full FMU of a mode: every variable, Eqs. (10)-(11), both steppers and schemes."""
        body = mode == "body"
        skeleton = cls(
            name=f"full_{mode}",
            mode=mode,
            inputs={"body": ("P",), "contact": ("P", "Vx", "Omega_y"), "rigid_body": ("Tx",)}[mode],
            outputs=(),
            methods=METHODS if body else ("full",),
            schemes=SCHEMES if body else SCHEMES[:1],
            vy="eq10" if body else "zero",
            spin="eq11" if body else "zero",
        )
        return cls(
            name=skeleton.name,
            mode=mode,
            inputs=tuple(fv.available(skeleton, fv.INPUT)),
            outputs=tuple(fv.available(skeleton, fv.OUTPUT)),
            methods=skeleton.methods,
            schemes=skeleton.schemes,
            vy=skeleton.vy,
            spin=skeleton.spin,
            description=f"Full {mode}-mode FMU: every variable and model part",
        )
