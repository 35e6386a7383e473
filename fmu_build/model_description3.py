"""The FMI 3.0 model description and build description of the native FMU (--native --fmi3).

Written from the same declarations as the FMI 2.0 one (``model_description.patch``):
the variables of ``contact_fmu.fmu.variables`` with the same value references, names,
causalities, variabilities, units, ranges and starts, Real as Float64, Integer as Int32,
String with a <Start> element; the same UnitDefinitions, LogCategories and
DefaultExperiment; ModelStructure with an Output per output and the FMI 2.0 FMU's direct
dependencies (value references here, indices there) and an InitialUnknown per output
(dependent on all knowns, as there). FMI 3.0 requires one independent variable: ``time``,
value reference ``len(cfg.variables)`` (after the model's), which fmi3.c reads as the
FMU's time. The CoSimulation capabilities are the FMI 2.0 FMU's, in FMI 3.0's names,
with adjoint derivatives where the directional ones are provided (contact mode).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from xml.dom import minidom

from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig

TYPES = {"Real": "Float64", "Integer": "Int32", "String": "String"}
LOG_CATEGORIES = (
    ("logStatusWarning", "Log messages with fmi3Warning status."),
    ("logStatusDiscard", "Log messages with fmi3Discard status."),
    ("logStatusError", "Log messages with fmi3Error status."),
    ("logStatusFatal", "Log messages with fmi3Fatal status."),
    ("logAll", "Log all messages."),
)


# The traction along the contact's centre line y = 0 as three Float64 arrays of LINE_N
# cells (FMI 3.0 arrays, fixed size): the cells' x and the traction there, at the
# outputs' kinematics (thin_layer.LayerContact.traction with ny = 1; native cf_get_line). After
# time's value reference, in this order. The C side's CF_LINE_N is LINE_N (cf_model.h).
LINE_N = 41
LINE = (
    ("x_centre", "m", "x of the cells along the contact's centre line y = 0, ascending"),
    ("tau_x_centre", "Pa", "traction tau_x along the centre line y = 0 (Eqs. 35-36)"),
    ("tau_y_centre", "Pa", "traction tau_y along the centre line y = 0 (Eqs. 35-36)"),
)


def has_line(cfg: ModelConfig) -> bool:
    """Whether the FMU has the centre line's arrays: the thin-layer law in body and
    contact mode, steady phase (native model.h's CF_LINE; the steady law's line would not
    be a transient field's)."""
    return cfg.mode != "rigid_body" and not cfg.has_table and not cfg.transient


def line_vrs(cfg: ModelConfig) -> dict[str, int]:
    """The arrays' value references (after time's), {} where the FMU has none."""
    if not has_line(cfg):
        return {}
    return {name: time_vr(cfg) + 1 + i for i, (name, _, _) in enumerate(LINE)}


def _num(x: float) -> str:
    return repr(float(x))


def time_vr(cfg: ModelConfig) -> int:
    """The value reference of the independent variable time (fmi3.c's CF3_VR_TIME)."""
    return len(cfg.variables)


def model_description(cfg: ModelConfig, identifier: str, token: str) -> bytes:
    """modelDescription.xml (FMI 3.0) of the native FMU of ``cfg``."""
    root = ET.Element(
        "fmiModelDescription",
        fmiVersion="3.0",
        modelName=identifier,
        instantiationToken=token,
        description=cfg.description or f"Spector & Batra (1995) contact, {cfg.mode} mode",
        author="contact_fmu",
        license="MIT",
        generationTool="contact_fmu fmu_build --native --fmi3",
        variableNamingConvention="structured",
    )
    derivatives = "true" if cfg.mode == "contact" else "false"
    ET.SubElement(
        root,
        "CoSimulation",
        modelIdentifier=identifier,
        needsExecutionTool="false",
        canBeInstantiatedOnlyOncePerProcess="false",
        canGetAndSetFMUState="true",
        canSerializeFMUState="true",
        # the contact mode's force element, for masters that couple implicitly
        providesDirectionalDerivatives=derivatives,
        providesAdjointDerivatives=derivatives,
        canHandleVariableCommunicationStepSize="true",
        maxOutputDerivativeOrder="0",
        providesIntermediateUpdate="false",
        mightReturnEarlyFromDoStep="false",
        canReturnEarlyAfterIntermediateUpdate="false",
        hasEventMode="false",
    )
    declared = cfg.variables
    units = {v.unit for v in declared if v.type == "Real"} | {"s"}
    units = sorted(units | ({unit for _, unit, _ in LINE} if has_line(cfg) else set()))
    defs = ET.SubElement(root, "UnitDefinitions")
    for name in units:
        unit = ET.SubElement(defs, "Unit", name=name)
        if fv.UNITS[name]:
            ET.SubElement(unit, "BaseUnit", {k: str(e) for k, e in fv.UNITS[name].items()})
    cats = ET.SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES:
        ET.SubElement(cats, "Category", name=name, description=text)
    if cfg.experiment is not None:
        start, stop, step = cfg.experiment
        ET.SubElement(
            root,
            "DefaultExperiment",
            startTime=_num(start),
            stopTime=_num(stop),
            stepSize=_num(step),
        )
    mv = ET.SubElement(root, "ModelVariables")
    ET.SubElement(
        mv,
        "Float64",
        name="time",
        valueReference=str(time_vr(cfg)),
        description="Simulation time",
        causality="independent",
        variability="continuous",
        unit="s",
    )
    for (name, unit, text), vr in zip(LINE, line_vrs(cfg).values(), strict=False):
        el = ET.SubElement(
            mv, "Float64", name=name, valueReference=str(vr), description=text,
            causality="output", variability="continuous", initial="calculated", unit=unit,
        )  # fmt: skip
        ET.SubElement(el, "Dimension", start=str(LINE_N))
    for vr, v in enumerate(declared):
        c = v.causality[cfg.mode]
        attrs = {"name": v.name, "valueReference": str(vr), "description": v.description}
        attrs |= {"causality": c, "variability": fv.variability(v, cfg.mode)}
        if c == fv.OUTPUT:
            attrs["initial"] = "calculated"
        lo, hi = cfg.bounds(v)  # min = max for a value the build fixes
        if v.type == "Real":
            attrs["unit"] = v.unit
            if lo is not None:
                attrs["min"] = _num(lo)
            if hi is not None:
                attrs["max"] = _num(hi)
            if c != fv.OUTPUT:
                attrs["start"] = _num(cfg.start(v))
        elif v.type == "Integer":
            if lo is not None:
                attrs["min"] = str(int(lo))
            if hi is not None:
                attrs["max"] = str(int(hi))
            if c != fv.OUTPUT:
                attrs["start"] = str(int(cfg.start(v)))
        el = ET.SubElement(mv, TYPES[v.type], attrs)
        if v.type == "String" and c != fv.OUTPUT:
            ET.SubElement(el, "Start", value=str(cfg.start(v)))
    structure = ET.SubElement(root, "ModelStructure")
    outputs = [vr for vr, v in enumerate(declared) if v.causality[cfg.mode] == fv.OUTPUT]
    inputs = {v.name: vr for vr, v in enumerate(declared) if v.causality[cfg.mode] == fv.INPUT}
    # the line follows the contact's kinematics and load as Tx does
    feedthrough = {vr: declared[vr].feedthrough for vr in outputs}
    tx = fv.BY_NAME["Tx"].feedthrough
    outputs += list(line_vrs(cfg).values())
    for vr in outputs:
        deps = []
        if cfg.mode == "contact":  # a force element: outputs follow the inputs directly
            deps = sorted(inputs[n] for n in feedthrough.get(vr, tx) if n in inputs)
        ET.SubElement(
            structure, "Output", valueReference=str(vr), dependencies=" ".join(map(str, deps))
        )
    for vr in outputs:
        ET.SubElement(structure, "InitialUnknown", valueReference=str(vr))
    text = ET.tostring(root, encoding="unicode")
    return minidom.parseString(text).toprettyxml(indent="  ", encoding="UTF-8")


def build_description(identifier: str, sources: tuple[str, ...]) -> bytes:
    """sources/buildDescription.xml (FMI 3.0): the C files (fmi3.c and the instance layer's,
    each its own translation unit), C11, linked with the C library's math library."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ET.SubElement(root, "BuildConfiguration", modelIdentifier=identifier)
    files = ET.SubElement(config, "SourceFileSet", language="C11")
    for name in sources:
        ET.SubElement(files, "SourceFile", name=name)
    ET.SubElement(
        config, "Library", name="m", external="true", description="the C math library (libm)"
    )
    text = ET.tostring(root, encoding="unicode")
    return minidom.parseString(text).toprettyxml(indent="  ", encoding="UTF-8")
