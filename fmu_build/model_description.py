"""Complete pythonfmu's modelDescription.xml from the variable declarations.

pythonfmu 0.7.0 writes no units, no min/max, starts with 16 digits and a ModelStructure
with outputs only. From ``contact_fmu.fmu.variables`` this adds UnitDefinitions and the
``unit``/``min``/``max`` attributes, writes exact (17-digit) start values, and rebuilds
ModelStructure: Outputs with their direct dependencies on inputs, InitialUnknowns with
every output (all are initial="calculated").
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from xml.dom import minidom

from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig

# Order of the children of fmiModelDescription in the FMI 2.0 schema.
_ORDER = (
    "ModelExchange",
    "CoSimulation",
    "UnitDefinitions",
    "TypeDefinitions",
    "LogCategories",
    "DefaultExperiment",
    "VendorAnnotations",
    "ModelVariables",
    "ModelStructure",
)


class ModelDescriptionError(RuntimeError):
    """pythonfmu's model description does not match the declarations."""


def _num(x: float) -> str:
    return repr(float(x))


def patch(
    xml: bytes, cfg: ModelConfig, model_identifier: str | None = None, guid: str | None = None
) -> bytes:
    """The completed model description of an FMU built for ``cfg``; with
    ``model_identifier`` it is the modelName and CoSimulation's modelIdentifier, with
    ``guid`` the GUID (pythonfmu writes its class name and a random one)."""
    root = ET.fromstring(xml)
    if model_identifier is not None:
        root.set("modelName", model_identifier)
        root.find("CoSimulation").set("modelIdentifier", model_identifier)
    if guid is not None:
        root.set("guid", guid)
    for el in root.iter():  # drop pythonfmu's indentation; the output is re-indented
        if el.text is not None and not el.text.strip():
            el.text = None
        if el.tail is not None and not el.tail.strip():
            el.tail = None
    declared = cfg.variables
    scalars = root.find("ModelVariables").findall("ScalarVariable")
    names = [sv.get("name") for sv in scalars]
    if names != [v.name for v in declared]:
        raise ModelDescriptionError(f"variables {names} != declared {[v.name for v in declared]}")
    index = {v.name: i + 1 for i, v in enumerate(declared)}  # 1-based, as in ModelStructure
    units = []
    for sv, var in zip(scalars, declared, strict=True):
        typed = sv.find(var.type)
        if typed is None:
            raise ModelDescriptionError(f"{var.name}: no <{var.type}> element")
        if var.type == "Real":
            typed.set("unit", var.unit)
            units.append(var.unit)
            lo, hi = cfg.bounds(var)  # min = max for a value the build fixes
            if lo is not None:
                typed.set("min", _num(lo))
            if hi is not None:
                typed.set("max", _num(hi))
            if typed.get("start") is not None:
                typed.set("start", _num(cfg.start(var)))
        elif var.type == "Integer":  # e.g. the field's grid sizes (phase "transient")
            lo, hi = cfg.bounds(var)
            if lo is not None:
                typed.set("min", str(int(lo)))
            if hi is not None:
                typed.set("max", str(int(hi)))

    unit_defs = ET.Element("UnitDefinitions")
    for name in sorted(set(units)):
        unit = ET.SubElement(unit_defs, "Unit", name=name)
        exps = fv.UNITS[name]
        if exps:
            ET.SubElement(unit, "BaseUnit", {k: str(e) for k, e in exps.items()})

    structure = ET.Element("ModelStructure")
    outputs = [v for v in declared if v.causality[cfg.mode] == fv.OUTPUT]
    inputs = {v.name for v in declared if v.causality[cfg.mode] == fv.INPUT}
    if outputs:
        node = ET.SubElement(structure, "Outputs")
        for v in outputs:
            deps = []
            if cfg.mode == "contact":  # a force element: outputs follow the inputs directly
                deps = sorted(index[n] for n in v.feedthrough if n in inputs)
            ET.SubElement(
                node, "Unknown", index=str(index[v.name]), dependencies=" ".join(map(str, deps))
            )
        init = ET.SubElement(structure, "InitialUnknowns")
        for v in outputs:
            ET.SubElement(init, "Unknown", index=str(index[v.name]))

    children = [c for c in root if c.tag not in ("UnitDefinitions", "ModelStructure")]
    children += [unit_defs, structure] if units else [structure]
    for c in list(root):
        root.remove(c)
    for c in sorted(children, key=lambda c: _ORDER.index(c.tag)):
        root.append(c)
    text = ET.tostring(root, encoding="unicode")
    return minidom.parseString(text).toprettyxml(indent="  ", encoding="UTF-8")
