"""The coupled system of a scene: a contact-mode FMU and a rigid_body-mode FMU.

A body-mode scene's model splits into two FMUs that a master couples: the force element
(contact mode: Vx, Omega_y and P in, Tx out) and the rigid body of Eqs. (8)-(9) (Tx,
Fx_ex, My_ex in, Vx, Omega_y out). ``write`` builds both FMUs with the scene's values as
their start values and writes the system twice:

- ``<name>.ssp``: SSP 1.0 (SystemStructure.ssd with the two components, their
  connectors, the three connections, the parameter values as a ParameterBinding of the
  system, the default experiment with the communication step as OSP's annotation
  ``<osp:FixedStepAlgorithm baseStepSize=.../>``; the FMUs under resources/). libcosim
  runs it as written (``CosimExecution.from_ssp_file``; without the annotation it ends
  the process); fmpy's ``fmpy.ssp.simulation.simulate_ssp`` reads neither the step nor
  the stop time from the file (it takes stop_time 1 s and step stop_time/100 unless
  given): pass ``stop_time`` and ``step_size``, which the command prints;
- ``OspSystemStructure.xml`` with the FMUs beside it: libcosim's format
  (``CosimExecution.from_osp_config_file``), the values as InitialValues.

The values are also the FMUs' start values, so a tool that ignores parameter bindings
(fmpy's simulate_ssp applies only the parameter set passed to it) runs the same system.
The inputs that are not connected (P, Fx_ex, My_ex) are held at the FMUs' start values
and are not connectors of the SSD: fmpy's SSP reader requires every input connector to
be connected (it fails on one that is not).

Explicit coupling and the step. A master exchanges Tx once per step, so the slip
equation M A2 dvx/dt = -Tx(vx) + ... is integrated explicitly with a delay of one step:
stable only for h below the slip relaxation time tau = M A2 |Vx| / (dTx/dxi), at first
order in h/tau (tests/test_cosim_libcosim.py derives the bound). The default step is
the power of ten at or below tau/5 (``contact_fmu.dynamics.coupling.relaxation_time``).

Inputs: the system files hold them constant (SSP and OSP carry no signals); a scene's
input that varies in time is refused unless a value is given (``overrides``).
"""

from __future__ import annotations

import math
import shutil
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.dom import minidom

import numpy as np

from contact_fmu._validate import InputError
from contact_fmu.dynamics.coupling import relaxation_time
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.factory import make_body, make_law
from contact_fmu.scenario.schema import Case, Scene

from . import DEFAULT_OUT, build, tables

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
# OSP's annotations of an SSD (libcosim's SSP reader matches the prefix "osp:" by name)
OSP_SSP = "http://opensimulationplatform.com/SSP/OSPAnnotations"
OSP_ANNOTATION = "com.opensimulationplatform"
# the components and their connections: (from, variable) -> (to, variable)
CONTACT, BODY = "contact", "body"
CONNECTIONS = (
    ((BODY, "Vx"), (CONTACT, "Vx")),
    ((BODY, "Omega_y"), (CONTACT, "Omega_y")),
    ((CONTACT, "Tx"), (BODY, "Tx")),
)
CONTACT_IO = (("P", "Vx", "Omega_y"), ("Tx", "vx", "xi_x", "adhesion", "regime"))
BODY_IO = (("Tx", "Fx_ex", "My_ex"), ("Vx", "Omega_y"))
# default step: the power of ten at or below tau / STEP_FRACTION
STEP_FRACTION = 5.0


@dataclass(frozen=True)
class System:
    """What ``write`` made: the files, the configurations, the step (s) and tau (s)."""

    ssp: Path
    osp: Path
    fmus: dict[str, Path]
    configs: dict[str, ModelConfig]
    step: float
    stop_time: float
    tau: float


def configs(scene: Scene, case: Case, overrides: dict[str, float]) -> dict[str, ModelConfig]:
    """The contact-mode and rigid_body-mode configurations of ``scene``'s case, with its
    parameters and (constant) inputs as start values."""
    cfg = scene.config
    if cfg.mode != "body" or cfg.vy != "zero" or cfg.spin != "zero" or cfg.transient:
        raise InputError(
            "scene",
            scene.name,
            "a planar body-mode scene (vy = spin = 0, phase steady): the system couples "
            "Vx, Omega_y and Tx",
        )
    t = scene.grid
    values: dict[str, Any] = dict(case.parameters)
    for name, signal in case.inputs.items():
        series = np.asarray(signal(t), float)
        if name not in overrides and np.any(series != series[0]):
            raise InputError(
                name,
                f"{series.min():g} .. {series.max():g} (case {case.name!r})",
                "constant in a system file (SSP and OSP carry no signals): give a value "
                f"with --set {name}=VALUE",
            )
        values[name] = float(series[0])
    unknown = set(overrides) - {v.name for v in ModelConfig.full("body").variables}
    if unknown:
        raise InputError("--set", sorted(unknown), "names of body-mode variables")
    values.update(overrides)
    out = {}
    for comp, mode, (inputs, outputs) in (
        (CONTACT, "contact", CONTACT_IO),
        (BODY, "rigid_body", BODY_IO),
    ):
        skeleton = ModelConfig(
            name=f"{scene.name}_{comp}",
            mode=mode,
            inputs=inputs,
            outputs=outputs,
            contact_law=cfg.contact_law if mode == "contact" else "layer",
            law_spec=cfg.law_spec if mode == "contact" else {},
        )
        starts = {
            v.name: values[v.name]
            for v in skeleton.variables
            if v.name in values and v.name not in skeleton.fixed
        }
        out[comp] = ModelConfig.from_dict(
            {
                **skeleton.to_dict(),
                "starts": starts,
                "description": f"{scene.title} ({mode} mode, case {case.name})",
            }
        )
    return out


def _values(cfg: ModelConfig) -> list[tuple[fv.Var, Any]]:
    """The parameters and unconnected inputs of an FMU with their start values (Reals);
    the connected inputs take what the master exchanges."""
    connected = {end[1] for _, end in CONNECTIONS}
    return [
        (v, cfg.start(v))
        for v in cfg.variables
        if v.type == "Real"
        and v.causality[cfg.mode] != fv.OUTPUT
        and not (v.causality[cfg.mode] == fv.INPUT and v.name in connected)
    ]


def _pretty(root: ET.Element) -> bytes:
    return minidom.parseString(ET.tostring(root)).toprettyxml(indent="  ", encoding="UTF-8")


def ssd(
    name: str, cfgs: dict[str, ModelConfig], sources: dict[str, str], stop: float, step: float
) -> bytes:
    """SystemStructure.ssd (SSP 1.0), fixed-step at ``step`` (s) for OSP's tools."""
    ET.register_namespace("ssd", SSD)
    ET.register_namespace("ssc", SSC)
    ET.register_namespace("ssv", SSV)
    ET.register_namespace("osp", OSP_SSP)
    d, c, v = (f"{{{ns}}}" for ns in (SSD, SSC, SSV))
    root = ET.Element(f"{d}SystemStructureDescription", version="1.0", name=name)
    system = ET.SubElement(root, f"{d}System", name=name)
    bindings = ET.SubElement(system, f"{d}ParameterBindings")
    pset = ET.SubElement(
        ET.SubElement(ET.SubElement(bindings, f"{d}ParameterBinding"), f"{d}ParameterValues"),
        f"{v}ParameterSet",
        version="1.0",
        name="parameters",
    )
    params = ET.SubElement(pset, f"{v}Parameters")
    elements = ET.SubElement(system, f"{d}Elements")
    ends = {end for _, end in CONNECTIONS}
    units = set()
    for comp, cfg in cfgs.items():
        el = ET.SubElement(
            elements,
            f"{d}Component",
            name=comp,
            type="application/x-fmu-sharedlibrary",
            source=sources[comp],
        )
        conns = ET.SubElement(el, f"{d}Connectors")
        for var in cfg.variables:
            kind = var.causality[cfg.mode]
            if kind == fv.INPUT and (comp, var.name) not in ends:
                continue  # a held input: the FMU's start value (fmpy needs inputs connected)
            connector = ET.SubElement(conns, f"{d}Connector", name=var.name, kind=kind)
            if var.type == "Real":
                ET.SubElement(connector, f"{c}Real", unit=var.unit)
                units.add(var.unit)
            else:
                ET.SubElement(connector, f"{c}{var.type}")
        for var, value in _values(cfg):
            if var.causality[cfg.mode] != fv.PARAMETER:
                continue
            p = ET.SubElement(params, f"{v}Parameter", name=f"{comp}.{var.name}")
            ET.SubElement(p, f"{v}Real", value=repr(float(value)), unit=var.unit)
    connections = ET.SubElement(system, f"{d}Connections")
    for (a, x), (b, y) in CONNECTIONS:
        ET.SubElement(
            connections,
            f"{d}Connection",
            startElement=a,
            startConnector=x,
            endElement=b,
            endConnector=y,
        )
    unit_defs = ET.SubElement(root, f"{d}Units")
    for u in sorted(units):
        unit = ET.SubElement(unit_defs, f"{c}Unit", name=u)
        ET.SubElement(unit, f"{c}BaseUnit", {k: str(e) for k, e in fv.UNITS[u].items()})
    experiment = ET.SubElement(root, f"{d}DefaultExperiment", startTime="0.0", stopTime=repr(stop))
    note = ET.SubElement(
        ET.SubElement(experiment, f"{d}Annotations"), f"{c}Annotation", type=OSP_ANNOTATION
    )
    algorithm = ET.SubElement(note, f"{{{OSP_SSP}}}Algorithm")
    ET.SubElement(algorithm, f"{{{OSP_SSP}}}FixedStepAlgorithm", baseStepSize=repr(step))
    return _pretty(root)


def osp(cfgs: dict[str, ModelConfig], sources: dict[str, str], step: float) -> bytes:
    """OspSystemStructure.xml (libcosim), fixed-step at ``step`` (s)."""
    ET.register_namespace("", OSP)
    o = f"{{{OSP}}}"
    root = ET.Element(f"{o}OspSystemStructure", version="0.1")
    ET.SubElement(root, f"{o}StartTime").text = "0.0"
    ET.SubElement(root, f"{o}BaseStepSize").text = repr(step)
    ET.SubElement(root, f"{o}Algorithm").text = "fixedStep"
    sims = ET.SubElement(root, f"{o}Simulators")
    for comp, cfg in cfgs.items():
        sim = ET.SubElement(sims, f"{o}Simulator", name=comp, source=sources[comp])
        initial = ET.SubElement(sim, f"{o}InitialValues")
        for var, value in _values(cfg):
            iv = ET.SubElement(initial, f"{o}InitialValue", variable=var.name)
            ET.SubElement(iv, f"{o}Real", value=repr(float(value)))
    connections = ET.SubElement(root, f"{o}Connections")
    for (a, x), (b, y) in CONNECTIONS:
        vc = ET.SubElement(connections, f"{o}VariableConnection")
        ET.SubElement(vc, f"{o}Variable", simulator=a, name=x)
        ET.SubElement(vc, f"{o}Variable", simulator=b, name=y)
    return _pretty(root)


def default_step(cfgs: dict[str, ModelConfig]) -> tuple[float, float]:
    """(step, tau): the power of ten at or below tau / STEP_FRACTION, and tau (s)."""
    contact, body = cfgs[CONTACT], cfgs[BODY]
    c = {v.name: contact.start(v) for v in contact.variables}
    b = {v.name: body.start(v) for v in body.variables}
    # the half-space law's table as the FMU carries it (the build's cache)
    table = tables.ensure(contact) if contact.has_table else None
    law = make_law(contact, c, c["P"], table=table)
    tau = relaxation_time(law, make_body(b), b["Vx0"])
    if not (tau > 0.0 and math.isfinite(tau)):
        raise InputError(
            "Vx0", b["Vx0"], "nonzero, with Iy > 0, for a default step (tau = 0): give --step"
        )
    return 10.0 ** math.floor(math.log10(tau / STEP_FRACTION)), tau


def write(
    scene: Scene,
    case: Case,
    folder: str | Path,
    step: float | None = None,
    overrides: dict[str, float] | None = None,
    fmu_out: str | Path = DEFAULT_OUT,
    native: bool = False,
) -> System:
    """Build the two FMUs (``native``: the native C FMUs, fmu_build.native_fmu) and
    write the system files into ``folder``."""
    folder = Path(folder)
    cfgs = configs(scene, case, dict(overrides or {}))
    auto, tau = default_step(cfgs)
    step = auto if step is None else float(step)
    ns = step * 1e9 if step > 0.0 and math.isfinite(step) else 0.0
    if not (ns >= 1.0 and abs(ns - round(ns)) <= 1e-9 * ns):
        raise InputError("step", step, "> 0 and a whole number of nanoseconds (libcosim)")
    folder.mkdir(parents=True, exist_ok=True)
    fmus = {}
    if native:
        from . import native_fmu
    for comp, cfg in cfgs.items():
        built = native_fmu.build(cfg, fmu_out) if native else build(cfg, fmu_out)
        fmus[comp] = folder / f"{cfg.name}{'_native' if native else ''}.fmu"
        shutil.copyfile(built.path, fmus[comp])
    sources = {comp: f"resources/{p.name}" for comp, p in fmus.items()}
    ssp_path = folder / f"{scene.name}.ssp"
    tmp = ssp_path.with_suffix(".ssp.tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd(scene.name, cfgs, sources, scene.stop_time, step))
        for comp, p in fmus.items():
            z.write(p, sources[comp])
    tmp.replace(ssp_path)
    osp_path = folder / "OspSystemStructure.xml"
    osp_path.write_bytes(osp(cfgs, {c: p.name for c, p in fmus.items()}, step))
    return System(ssp_path, osp_path, fmus, cfgs, step, scene.stop_time, tau)
