"""A scene as an SSP 1.0 package (``tribocosim ssp export SCENE -o RIG.ssp``).

The zip holds

- ``SystemStructure.ssd``: one ``ssd:System`` named after the scene, with

  - an ``ssd:Component`` per FMU instance, in scene order, ``source="resources/<FMU>.fmu"``;
  - its connectors: every numeric output, and every input a connection feeds, typed as in the FMU and
    with its unit (``<ssc:Real unit="N"/>``; the units' SI base exponents under ``ssd:Units``).
    Unconnected inputs get no connector: they keep their start value or the parameter set's value
    (fmpy 0.3's ``simulate_ssp`` drives every declared input connector, with 0 when unconnected);
  - its scene parameters as an ``ssd:ParameterBinding`` to ``resources/<instance>.ssv`` (names as in
    the FMU, values with the FMU's units). Every ``ssv:ParameterSet`` has the same name, the system's
    (the scene file's stem, e.g. ``demo``), so that one named set holds all of them: ecos applies the
    sets of the one name it is given (``EcosSimulation.init(parameter_set="demo")``); libcosim and
    OMSimulator apply the component bindings as they are; fmpy 0.3's ``simulate_ssp`` applies only
    the one ``parameter_set`` it is given, with ``component.variable`` names
    (:func:`tribocosim.cosim.ssp.names.fmpy_parameter_set` gathers the bindings into one);
  - the connections, in scene order;
  - ``ssd:Annotations``, last: first OMSimulator's (``org.openmodelica``: ``oms:SimulationInformation``
    with an ``oms:FixedStepMaster`` of the scene's step; OMSimulator reads the first annotation only,
    and without it cannot make the system), then the ``org.tribocosim.scene`` annotation: the scene's
    ``[master]``, ``[[power_bonds]]`` and ``[output]`` tables as TOML, for ``tribocosim run RIG.ssp``;

- ``ssd:DefaultExperiment``: start and stop time, and the master step as the OSP annotation
  ``osp:FixedStepAlgorithm baseStepSize`` (libcosim reads it; SSP 1.0 has no element for it); for an
  adaptive scene that is the initial step;
- ``resources/``: each distinct FMU file once, and the ``.ssv`` parameter sets.

No annotation at the top level of the SSD: OMSimulator's reader takes only ``ssd:System``,
``ssd:Units``, ``ssd:Enumerations`` and ``ssd:DefaultExperiment`` there ("wrong xml schema detected").

Members are written in a fixed order with a fixed timestamp, so the same scene and FMUs give the
same bytes. The FMUs are copied as they are: a native FMU from the cache carries this machine's binary
only (``linux64`` here), which is then the platform the package runs on. String parameters go into
the ``.ssv`` as they are, so a file they name (``field_output``, a ``table_file`` outside the FMU) must
exist where the package runs. Enumeration connectors are written as the standard says, with
``ssd:Enumerations``; libcosim's SSP reader stops at them (the project's FMUs have none).
"""

from __future__ import annotations

import hashlib
import re
import tomllib
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

from tribocosim.errors import TribocosimError
from tribocosim.cosim.scene.schema import apply_overrides
from tribocosim.cosim.ssp.names import (FMU_TYPE, NS, OMS_ANNOTATION, OSP_ANNOTATION, PARAMETER_SET_TYPE, SCENE_ANNOTATION,
                                  SCENE_TABLES, SSD_NAME, q, toml_text)
from tribocosim.cosim.scene.validate import unit_of

_CONNECTOR_TYPES = ("Real", "Integer", "Boolean", "Enumeration")
_BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
_EPOCH = (1980, 1, 1, 0, 0, 0)


@dataclass(frozen=True)
class Package:
    """What :func:`export_ssp` wrote.

    Attributes
    ----------
    path : Path
        The .ssp file.
    components : tuple of str
        Instance names, in scene order.
    connections : int
        Number of ``ssd:Connection`` elements.
    parameters : int
        Number of parameter values in the ``.ssv`` files.
    resources : tuple of str
        The members under ``resources/``.
    """

    path: Path
    components: tuple[str, ...]
    connections: int
    parameters: int
    resources: tuple[str, ...]


def export_ssp(scene: str | Path, out: str | Path, overrides: dict | None = None) -> Package:
    """Write a scene as an SSP 1.0 package.

    Parameters
    ----------
    scene : str or Path
        The scene file (validated first, its component FMUs built into the cache when missing).
    out : str or Path
        The .ssp file to write (replaced atomically).
    overrides : dict, optional
        Dotted scene keys to set first, as ``tribocosim run --set`` does.

    Raises
    ------
    SceneError
        If the scene has problems.
    TribocosimError
        If two FMUs define the same unit name differently.
    """
    from tribocosim.cosim.scene.validate import load_scene

    out = Path(out)
    _check_out(out)  # before the scene's FMUs are built
    plan = load_scene(scene, overrides)
    sc = plan.scene
    doc = apply_overrides(tomllib.loads(sc.path.read_text(encoding="utf-8")), dict(overrides or {}))
    for prefix in ("ssd", "ssc", "ssv", "osp", "oms", "tc"):
        ET.register_namespace(prefix, NS[prefix])

    fmu_member, fmu_files = _fmu_members(plan)
    units, enums = _Units(), {}
    root = ET.Element(q("ssd:SystemStructureDescription"),
                      {"version": "1.0", "name": sc.path.stem, "generationTool": _tool()})
    system = ET.SubElement(root, q("ssd:System"), {"name": sc.path.stem,
                                                   "description": f"scene {sc.path.name}, exported by tribocosim"})
    elements = ET.SubElement(system, q("ssd:Elements"))
    connected = {(l.target.instance, l.target.variable) for l in plan.links}
    ssv_files: dict[str, bytes] = {}
    n_parameters = 0
    for name, model in plan.fmus.items():
        comp = ET.SubElement(elements, q("ssd:Component"), {"name": name, "type": FMU_TYPE, "source": fmu_member[name],
                                                           "implementation": "CoSimulation"})
        ports = [v for v in model.md.modelVariables if v.type in _CONNECTOR_TYPES and
                 (v.causality == "output" or (v.causality == "input" and (name, v.name) in connected))]
        if ports:
            connectors = ET.SubElement(comp, q("ssd:Connectors"))
            for v in ports:
                c = ET.SubElement(connectors, q("ssd:Connector"), {"name": v.name, "kind": v.causality})
                _type_element(c, v, model, units, enums)
        params = sc.fmus[name].parameters
        if params:
            member = _unique(f"resources/{_safe(name)}", ".ssv", set(ssv_files) | set(fmu_files))
            ssv_files[member] = _parameter_set(sc.path.stem, model, params)
            n_parameters += len(params)
            bindings = ET.SubElement(comp, q("ssd:ParameterBindings"))
            ET.SubElement(bindings, q("ssd:ParameterBinding"), {"type": PARAMETER_SET_TYPE, "source": member})
    if plan.links:
        conns = ET.SubElement(system, q("ssd:Connections"))
        for l in plan.links:
            ET.SubElement(conns, q("ssd:Connection"), {
                "startElement": l.source.instance, "startConnector": l.source.variable,
                "endElement": l.target.instance, "endConnector": l.target.variable})
    ex = sc.experiment
    notes = ET.SubElement(system, q("ssd:Annotations"))
    oms = ET.SubElement(ET.SubElement(notes, q("ssc:Annotation"), {"type": OMS_ANNOTATION}), q("oms:Annotations"))
    ET.SubElement(ET.SubElement(oms, q("oms:SimulationInformation")), q("oms:FixedStepMaster"),
                  {"description": "oms-ma", "stepSize": repr(ex.step)})
    tables = {k: doc[k] for k in SCENE_TABLES if k in doc}
    if tables:
        note = ET.SubElement(notes, q("ssc:Annotation"), {"type": SCENE_ANNOTATION})
        ET.SubElement(note, q("tc:Scene"), {"format": "toml"}).text = "\n" + toml_text(tables)
    if enums:
        block = ET.SubElement(root, q("ssd:Enumerations"))
        for ename, items in enums.items():
            e = ET.SubElement(block, q("ssc:Enumeration"), {"name": ename})
            for item in items:
                ET.SubElement(e, q("ssc:Item"), {"name": item.name, "value": str(int(item.value))})
    if units.used:
        units.write(ET.SubElement(root, q("ssd:Units")))
    default = ET.SubElement(root, q("ssd:DefaultExperiment"), {"startTime": repr(ex.start), "stopTime": repr(ex.stop)})
    osp = ET.SubElement(ET.SubElement(default, q("ssd:Annotations")), q("ssc:Annotation"), {"type": OSP_ANNOTATION})
    ET.SubElement(ET.SubElement(osp, q("osp:Algorithm")), q("osp:FixedStepAlgorithm"), {"baseStepSize": repr(ex.step)})

    members = {SSD_NAME: _xml_bytes(root)}
    members.update({m: Path(p).read_bytes() for m, p in fmu_files.items()})
    members.update(ssv_files)
    _write_zip(out, members)
    return Package(out, tuple(plan.fmus), len(plan.links), n_parameters, tuple(m for m in members if m != SSD_NAME))


# ------------------------------------------------------------------ parts
class _Units:
    """The units used, with their SI base exponents from the FMUs' unit definitions."""

    def __init__(self) -> None:
        self.used: dict[str, tuple[dict, str]] = {}  # name -> (BaseUnit attributes, FMU that defined it)

    def add(self, unit: str, model) -> None:
        definition = next((u for u in model.md.unitDefinitions if u.name == unit), None)
        if definition is None:  # the FMU does not define it: the connector still names it
            return
        b = definition.baseUnit
        attrs = {} if b is None else {k: str(int(getattr(b, k))) for k in _BASE_UNITS if getattr(b, k)}
        if b is not None and b.factor != 1.0:
            attrs["factor"] = repr(float(b.factor))
        if b is not None and b.offset != 0.0:
            attrs["offset"] = repr(float(b.offset))
        known = self.used.get(unit)
        if known is not None and known[0] != attrs:
            raise TribocosimError(f"unit {unit!r} is defined differently by {known[1]} ({known[0]}) and by "
                                  f"{model.path.name} ({attrs}); an SSP package has one definition per unit name")
        self.used[unit] = (attrs, model.path.name)

    def write(self, parent: ET.Element, prefix: str = "ssc") -> None:
        for name, (attrs, _) in sorted(self.used.items()):
            ET.SubElement(ET.SubElement(parent, q(f"{prefix}:Unit"), {"name": name}), q(f"{prefix}:BaseUnit"), attrs)


def _type_element(connector: ET.Element, var, model, units: _Units, enums: dict) -> None:
    """The ``ssc:Real|Integer|Boolean|Enumeration`` child of a connector."""
    attrs = {}
    if var.type == "Real" and unit_of(var):
        attrs["unit"] = unit_of(var)
        units.add(attrs["unit"], model)
    elif var.type == "Enumeration":
        attrs["name"] = var.declaredType.name
        enums[var.declaredType.name] = var.declaredType.items
    ET.SubElement(connector, q(f"ssc:{var.type}"), attrs)


def _parameter_set(name: str, model, params: dict) -> bytes:
    """The ``.ssv`` file of one instance's scene parameters, a parameter set called ``name``."""
    root = ET.Element(q("ssv:ParameterSet"), {"version": "1.0", "name": name, "generationTool": _tool()})
    values = ET.SubElement(root, q("ssv:Parameters"))
    units = _Units()
    for pname, value in params.items():
        var = model.variables[pname]
        attrs = {}
        if var.type == "Real":
            attrs["value"] = repr(float(value))
            if unit_of(var):
                attrs["unit"] = unit_of(var)
                units.add(attrs["unit"], model)
        elif var.type == "Boolean":
            attrs["value"] = "true" if value else "false"
        elif var.type == "Enumeration":
            attrs["value"] = next((i.name for i in var.declaredType.items if int(i.value) == value), str(value))
            attrs["name"] = var.declaredType.name
        else:  # Integer, String
            attrs["value"] = str(value)
        ET.SubElement(ET.SubElement(values, q("ssv:Parameter"), {"name": pname}), q(f"ssv:{var.type}"), attrs)
    if units.used:
        units.write(ET.SubElement(root, q("ssv:Units")))
    return _xml_bytes(root)


def _fmu_members(plan) -> tuple[dict[str, str], dict[str, Path]]:
    """(instance -> ``resources/X.fmu``, member -> FMU file); one member per distinct file content."""
    by_digest: dict[str, str] = {}
    member_of: dict[str, str] = {}
    files: dict[str, Path] = {}
    for name, model in plan.fmus.items():
        digest = hashlib.sha256(model.path.read_bytes()).hexdigest()
        member = by_digest.get(digest)
        if member is None:
            member = by_digest[digest] = _unique(f"resources/{_safe(model.path.stem)}", ".fmu", set(files))
            files[member] = model.path
        member_of[name] = member
    return member_of, files


def _safe(name: str) -> str:
    """A file name from an instance or FMU name (relative URIs of plain characters, as libcosim reads them raw)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


def _unique(stem: str, suffix: str, taken: set[str]) -> str:
    member, k = f"{stem}{suffix}", 2
    while member in taken:
        member, k = f"{stem}-{k}{suffix}", k + 1
    return member


def _tool() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return f"tribocosim {version('tribocosim')}"
    except PackageNotFoundError:
        return "tribocosim"


def _xml_bytes(root: ET.Element) -> bytes:
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


def _check_out(out: Path) -> None:
    """TribocosimError naming ``out`` when a folder, or a file in place of a folder above it, is in its way."""
    if out.is_dir():
        raise TribocosimError(f"cannot write the SSP package {out}: it is a folder; allowed: a file name "
                              f"(e.g. {out / 'rig.ssp'})")
    above = next((p for p in out.parents if p.exists()), None)
    if above is not None and not above.is_dir():
        raise TribocosimError(f"cannot write the SSP package {out}: {above} is a file, not a folder")


def _write_zip(out: Path, members: dict[str, bytes]) -> None:
    """Write the members (in order, fixed timestamps) to ``out`` via a temporary file and a rename; an OS error is a
    TribocosimError naming ``out`` (not the temporary file)."""
    from tribocosim.atomic import replaced

    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        with replaced(out, ".ssp") as tmp, zipfile.ZipFile(tmp, "w") as zf:
            for name, data in members.items():
                info = zipfile.ZipInfo(name, date_time=_EPOCH)
                info.external_attr = 0o644 << 16  # rw-r--r-- for tools that apply it
                zf.writestr(info, data, compress_type=zipfile.ZIP_DEFLATED)
    except OSError as exc:
        raise TribocosimError(f"cannot write the SSP package {out}: {exc.strerror or exc}") from None
