"""An SSP 1.0 package run by our master (``tribocosim run RIG.ssp``).

:func:`load_ssp` extracts the package into a temporary folder (removed when the process ends),
reads ``SystemStructure.ssd``, translates the system into a scene, written next to the SSD as
``<package name>.toml`` with the FMU paths relative to it, and validates that scene as any other
(:func:`tribocosim.cosim.scene.validate.load_scene`, ``--set`` overrides applied on top).
:func:`tribocosim.cosim.api.run_ssp` runs it and records the package in the run's metadata.

What is read:

- one ``ssd:System`` of FMU components (co-simulation), each ``source`` a relative path inside the
  package, with their connectors (checked against the FMU: name, kind, type, unit);
- connections between component connectors (``startElement``/``endElement`` need not follow the
  data flow: the connectors' kinds give it);
- parameter bindings of parameter sets on the components and on the system (names then
  ``component.variable``): inline ``ssv:ParameterSet`` or a ``.ssv`` file in the package, with
  ``prefix``; later bindings win, and the system's win over the components' (SSP 1.0,
  ``ParameterBinding``). Names that match no variable are ignored, as the standard says (logged,
  and listed in the scene's header);
- ``ssd:DefaultExperiment`` start and stop, and the step from the OSP annotation
  ``osp:FixedStepAlgorithm baseStepSize`` (else ``--set experiment.step=...``);
- the ``org.tribocosim.scene`` annotation written by :mod:`tribocosim.cosim.ssp.export` (master
  settings, power bonds, recorded outputs), on the ``ssd:System`` or at the top level of the SSD (the
  system's wins). Without it: the default master (Jacobi, no
  extrapolation) and every output connector recorded, in document order, to ``<name>.csv``.

Refused, each problem naming the element (all of them in one SceneError): signal dictionaries
and their references, nested systems, system connectors and connections to them, components
that are not FMUs or asked for as Model Exchange, parameter mappings, ``sourceBase="component"``,
absolute or outside-the-package sources, connection transformations, units that would need a
conversion (a connector's or a parameter value's unit other than the FMU variable's, or two
connected connectors with different units), Binary values, ``inout`` and parameter connectors in
connections. Geometry, graphical elements and other tools' annotations are ignored.
"""

from __future__ import annotations

import atexit
import posixpath
import shutil
import tempfile
import tomllib
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote, urlsplit

from tribocosim.errors import Problem, SceneError
from tribocosim.lazy import WARNING, log
from tribocosim.cosim.scene.problems import Problems
from tribocosim.cosim.ssp.names import (FMU_TYPE, OSP_ANNOTATION, PARAMETER_SET_TYPE, SCENE_ANNOTATION, SCENE_TABLES, SSD_NAME,
                                  prefixed, q, toml_text)
from tribocosim.cosim.scene.validate import unit_of


_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration", "Binary")
_NUMERIC = ("Real", "Integer", "Boolean", "Enumeration")
_IGNORED = {"ssd:ElementGeometry", "ssd:SystemGeometry", "ssd:GraphicalElements", "ssd:Annotations",
            "ssd:ConnectorGeometry", "ssd:ConnectionGeometry", "ssd:Enumerations", "ssd:Units"}
_EXTRACTED: list[Path] = []


@dataclass
class _Component:
    """A component as read: its FMU (member and model description) and its declared connectors."""

    name: str
    member: str | None
    md: object | None
    connectors: dict[str, tuple[str, str | None, str]] = field(default_factory=dict)  # name -> (kind, unit, where)
    parameters: dict[str, object] = field(default_factory=dict)

    def variable(self, name: str):
        return None if self.md is None else next((v for v in self.md.modelVariables if v.name == name), None)


def load_ssp(path: str | Path, overrides: dict | None = None):
    """Read an SSP package as a validated scene (a :class:`tribocosim.cosim.scene.validate.Plan`).

    Parameters
    ----------
    path : str or Path
        The .ssp file.
    overrides : dict, optional
        Dotted scene keys to set on the translated scene, e.g. ``{"master.algorithm": "gauss-seidel"}``.

    Raises
    ------
    SceneError
        Listing every unsupported element and every problem of the translated scene, each with the
        package's path and the element (or the scene key).
    """
    from tribocosim.cosim.scene.validate import load_scene

    ssp = Path(path).resolve()
    folder = _extract(ssp)
    reader = _Reader(ssp, folder, dict(overrides or {}))
    doc = reader.read()
    reader.problems.raise_if_any()
    scene = folder / f"{ssp.stem}.toml"
    header = [f"# {ssp.name} (SSP 1.0) as a tribocosim scene, written by tribocosim.cosim.ssp.reader"]
    header += [f"# ignored (no such variable): {w}" for w in reader.ignored]
    scene.write_text("\n".join(header) + "\n\n" + toml_text(doc), encoding="utf-8")
    try:
        return load_scene(scene, overrides)
    except SceneError as exc:
        raise SceneError([Problem(str(ssp), p.key, p.message) for p in exc.problems],
                         f"SSP {ssp} (read as the scene {scene.name})") from None


def _extract(ssp: Path) -> Path:
    """Unzip the package into a temporary folder removed at exit."""
    if not ssp.is_file():
        raise SceneError(f"SSP package not found: {ssp}")
    if not zipfile.is_zipfile(ssp):
        raise SceneError(f"{ssp}: not an SSP package (a zip file with {SSD_NAME})")
    with zipfile.ZipFile(ssp) as zf:
        if SSD_NAME not in zf.namelist():
            raise SceneError(f"{ssp}: the package has no {SSD_NAME} (members: {', '.join(zf.namelist()[:20])})")
        if not _EXTRACTED:
            atexit.register(_cleanup)
        folder = Path(tempfile.mkdtemp(prefix=f"tribocosim-ssp-{ssp.stem}-"))
        _EXTRACTED.append(folder)
        zf.extractall(folder)  # zipfile drops absolute paths and '..' from member names
    return folder


def _cleanup() -> None:
    for d in _EXTRACTED:
        shutil.rmtree(d, ignore_errors=True)


class _Reader:
    """Reads one SSD into a scene document, collecting every problem."""

    def __init__(self, ssp: Path, folder: Path, overrides: dict) -> None:
        self.ssp, self.folder, self.overrides = ssp, folder, overrides
        self.problems = Problems(ssp, "SSP")
        self.add = self.problems.add
        self.components: dict[str, _Component] = {}
        self.ignored: list[str] = []
        self.system_tables: dict = {}

    # --- the document
    def read(self) -> dict:
        try:
            root = ET.parse(self.folder / SSD_NAME).getroot()
        except ET.ParseError as exc:
            self.add(SSD_NAME, f"not well-formed XML: {exc}")
            return {}
        if root.tag != q("ssd:SystemStructureDescription"):
            self.add(SSD_NAME, f"the root element is {prefixed(root.tag)}, not ssd:SystemStructureDescription "
                               "(namespace http://ssp-standard.org/SSP1/SystemStructureDescription)")
            return {}
        if not str(root.get("version", "")).startswith("1."):
            self.add("ssd:SystemStructureDescription", f"version {root.get('version')!r}: only SSP 1.0 is read")
        experiment, tables, connections = {}, {}, []
        system_bindings = []
        for child in root:
            tag = prefixed(child.tag)
            if tag == "ssd:System":
                system_bindings, connections = self._system(child, f"ssd:System[@name='{child.get('name')}']")
            elif tag == "ssd:DefaultExperiment":
                experiment = self._experiment(child)
            elif tag == "ssd:Annotations":
                tables = self._scene_annotation(child)
            elif tag not in _IGNORED:
                self.add(tag, "unknown element of ssd:SystemStructureDescription")
        if root.find(q("ssd:System")) is None:
            self.add("ssd:SystemStructureDescription", "no ssd:System")
        tables = self.system_tables or tables
        self._apply_bindings(system_bindings, None)
        for key, what in (("stop", "stopTime"), ("step", "step size (osp:FixedStepAlgorithm baseStepSize)")):
            if key not in experiment and f"experiment.{key}" not in self.overrides:
                self.add("ssd:DefaultExperiment", f"no {what}; give one with --set experiment.{key}=...")
        fmus = {}
        for c in self.components.values():
            fmus[c.name] = {"path": c.member or f"(missing {c.name})"}
            if c.parameters:
                fmus[c.name]["parameters"] = dict(c.parameters)
        doc = {"experiment": experiment}
        if "master" in tables:
            doc["master"] = tables["master"]
        doc["fmus"] = fmus
        if connections:
            doc["connections"] = connections
        if "power_bonds" in tables:
            doc["power_bonds"] = tables["power_bonds"]
        doc["output"] = tables.get("output", {"file": f"{self.ssp.stem}.csv", "variables": self._outputs()})
        return doc

    def _system(self, system: ET.Element, where: str):
        bindings, connections = [], []
        for child in system:
            tag = prefixed(child.tag)
            w = f"{where}/{tag}"
            if tag == "ssd:Elements":
                for el in child:
                    etag = prefixed(el.tag)
                    ew = f"{w}/{etag}[@name='{el.get('name')}']"
                    if etag == "ssd:Component":
                        self._component(el, ew)
                    elif etag == "ssd:System":
                        self.add(ew, "nested systems are not supported; flatten the system into one ssd:System")
                    elif etag == "ssd:SignalDictionaryReference":
                        self.add(ew, "signal dictionaries are not supported; connect the components directly")
                    else:
                        self.add(ew, "unknown element of ssd:Elements")
            elif tag == "ssd:Connections":
                for i, c in enumerate(child.findall(q("ssd:Connection")), 1):
                    link = self._connection(c, f"{w}/ssd:Connection[{i}]")
                    if link is not None:
                        connections.append(link)
            elif tag == "ssd:ParameterBindings":
                bindings = self._bindings(child, w)
            elif tag == "ssd:Connectors":
                self.add(w, "system connectors (an interface to an enclosing system) are not supported")
            elif tag == "ssd:SignalDictionaries":
                self.add(w, "signal dictionaries are not supported; connect the components directly")
            elif tag == "ssd:Annotations":
                self.system_tables = self._scene_annotation(child)
            elif tag not in _IGNORED:
                self.add(w, "unknown element of ssd:System")
        return bindings, connections

    # --- components and connectors
    def _component(self, el: ET.Element, where: str) -> None:
        from fmpy import read_model_description

        name = el.get("name", "")
        if name in self.components or not name or "." in name:
            self.add(where, "component names must be unique, non-empty and contain no '.'")
            return
        ctype = el.get("type", FMU_TYPE)
        if ctype != FMU_TYPE:
            self.add(where, f"type {ctype!r}: only FMU components ({FMU_TYPE}) are supported, not nested SSD/SSP")
        if el.get("implementation", "any") == "ModelExchange":
            self.add(where, "implementation 'ModelExchange': the master runs FMUs as co-simulation")
        member = self._member(el.get("source", ""), where, "source")
        md = None
        if member is not None and ctype == FMU_TYPE:
            try:
                md = read_model_description(str(self.folder / member), validate=False)
            except Exception as exc:  # any unreadable FMU: reported with the element
                self.add(where, f"cannot read the model description of {member}: {exc}")
        comp = self.components[name] = _Component(name, member, md)
        for child in el:
            tag = prefixed(child.tag)
            if tag == "ssd:Connectors":
                for c in child.findall(q("ssd:Connector")):
                    self._connector(comp, c, f"{where}/ssd:Connectors/ssd:Connector[@name='{c.get('name')}']")
            elif tag == "ssd:ParameterBindings":
                self._apply_bindings(self._bindings(child, f"{where}/{tag}"), comp)
            elif tag not in _IGNORED:
                self.add(f"{where}/{tag}", "unknown element of ssd:Component")

    def _connector(self, comp: _Component, c: ET.Element, where: str) -> None:
        name, kind = c.get("name", ""), c.get("kind", "")
        types = [ch for ch in c if prefixed(ch.tag).removeprefix("ssc:") in _TYPES]
        ctype = prefixed(types[0].tag).removeprefix("ssc:") if types else None
        unit = types[0].get("unit") if types else None
        comp.connectors[name] = (kind, unit, where)
        if comp.md is None:
            return
        var = comp.variable(name)
        if var is None:
            self.add(where, f"{comp.member} has no variable {name!r}")
            return
        if kind in ("input", "output", "parameter", "calculatedParameter") and var.causality != kind:
            self.add(where, f"kind {kind!r} does not match the FMU variable's causality {var.causality!r}")
        if ctype is not None and ctype != var.type:
            self.add(where, f"type ssc:{ctype} does not match the FMU variable's type {var.type}")
        if unit and unit_of(var) and unit != unit_of(var):
            self.add(where, f"unit {unit!r} differs from the FMU variable's {unit_of(var)!r}: unit conversions "
                            "are not supported")

    def _connection(self, c: ET.Element, where: str) -> dict | None:
        ends = [(c.get("startElement"), c.get("startConnector")), (c.get("endElement"), c.get("endConnector"))]
        ok = True
        for child in c:
            tag = prefixed(child.tag)
            if tag.endswith("Transformation"):
                self.add(f"{where}/{tag}", "transformations on connections are not supported")
                ok = False
        if any(e is None for e, _ in ends):
            self.add(where, "connections to the system's own connectors are not supported "
                            "(give startElement and endElement)")
            return None
        kinds, units = [], []
        for element, connector in ends:
            comp = self.components.get(element)
            if comp is None:
                self.add(where, f"unknown element {element!r}; components: {', '.join(self.components) or '(none)'}")
                return None
            declared = comp.connectors.get(connector)
            var = comp.variable(connector)
            if declared is None and var is None:
                if comp.md is not None:  # (an unreadable FMU is reported already)
                    self.add(where, f"{element!r} has no connector or FMU variable {connector!r}")
                return None
            kinds.append(declared[0] if declared else (var.causality if var is not None else None))
            units.append((declared[1] if declared else None) or (unit_of(var) if var is not None else None))
        if kinds == ["input", "output"]:
            ends.reverse()
            units.reverse()
        elif kinds != ["output", "input"]:
            self.add(where, f"connects a connector of kind {kinds[0]!r} to one of kind {kinds[1]!r}: only output -> "
                            "input connections are supported")
            return None
        if units[0] and units[1] and units[0] != units[1] and c.get("suppressUnitConversion", "false") != "true":
            self.add(where, f"{'.'.join(ends[0])} is in {units[0]!r} and {'.'.join(ends[1])} in {units[1]!r}: "
                            "unit conversions are not supported")
            ok = False
        return {"from": ".".join(ends[0]), "to": ".".join(ends[1])} if ok else None

    def _outputs(self) -> list[str]:
        names = []
        for comp in self.components.values():
            for name, (kind, _, _) in comp.connectors.items():
                var = comp.variable(name)
                if kind == "output" and var is not None and var.type in _NUMERIC:
                    names.append(f"{comp.name}.{name}")
        return names

    # --- parameters
    def _bindings(self, el: ET.Element, where: str) -> list[tuple[str, ET.Element, str]]:
        """The parameters of every binding, in order: (name with prefix, value element, where)."""
        found = []
        for i, b in enumerate(el.findall(q("ssd:ParameterBinding")), 1):
            bw = f"{where}/ssd:ParameterBinding[{i}]"
            if b.get("type", PARAMETER_SET_TYPE) != PARAMETER_SET_TYPE:
                self.add(bw, f"type {b.get('type')!r}: only SSP parameter sets ({PARAMETER_SET_TYPE}) are supported")
                continue
            if b.find(q("ssd:ParameterMapping")) is not None:
                self.add(f"{bw}/ssd:ParameterMapping", "parameter mappings are not supported; give the FMU's names")
                continue
            if b.get("sourceBase", "SSD") != "SSD":
                self.add(bw, "sourceBase 'component' (a parameter set inside the FMU) is not supported")
                continue
            pset = None
            if b.get("source") is not None:
                member = self._member(b.get("source"), bw, "source")
                if member is not None:
                    try:
                        pset = ET.parse(self.folder / member).getroot()
                    except ET.ParseError as exc:
                        self.add(bw, f"{member} is not well-formed XML: {exc}")
                        continue
            else:
                pset = b.find(f"{q('ssd:ParameterValues')}/{q('ssv:ParameterSet')}")
            if pset is None or pset.tag != q("ssv:ParameterSet"):
                if pset is not None or b.get("source") is None:
                    self.add(bw, "no ssv:ParameterSet (inline in ssd:ParameterValues, or the source file's root)")
                continue
            prefix = b.get("prefix", "")
            for p in pset.findall(f"{q('ssv:Parameters')}/{q('ssv:Parameter')}"):
                values = [ch for ch in p if prefixed(ch.tag).removeprefix("ssv:") in _TYPES]
                pw = f"{bw}//ssv:Parameter[@name='{p.get('name')}']"
                if not values:
                    self.add(pw, "no value (ssv:Real, ssv:Integer, ...)")
                    continue
                found.append((prefix + p.get("name", ""), values[0], pw))
        return found

    def _apply_bindings(self, params: list, comp: _Component | None) -> None:
        """Set the parameters of ``comp`` (or, for the system's bindings, of the component each name starts with)."""
        for name, value, where in params:
            target, var_name = comp, name
            if comp is None:
                head, _, var_name = name.partition(".")
                target = self.components.get(head)
            var = target.variable(var_name) if target is not None else None
            if var is None:
                if target is None or target.md is not None:
                    log(__name__, WARNING, "%s: %s: %s matches no variable; ignored", self.ssp.name, where, name)
                    self.ignored.append(f"{name} ({where})")
                continue
            converted = self._value(value, var, where)
            if converted is not None:
                target.parameters[var_name] = converted

    def _value(self, el: ET.Element, var, where: str):
        kind, text = prefixed(el.tag).removeprefix("ssv:"), el.get("value", "")
        try:
            if kind == "Binary":
                self.add(where, "Binary values are not supported")
            elif kind == "Enumeration" and var.type == "Enumeration":
                items = {i.name: int(i.value) for i in var.declaredType.items}
                if text in items:
                    return items[text]
                self.add(where, f"{text!r} is not an item of {var.declaredType.name}; items: {', '.join(items)}")
            elif kind == "Real" and var.type == "Real":
                unit = el.get("unit")
                if unit and unit_of(var) and unit != unit_of(var):
                    self.add(where, f"unit {unit!r} differs from the FMU variable's {unit_of(var)!r}: unit "
                                    "conversions are not supported")
                    return None
                return float(text)
            elif kind == "Integer" and var.type in ("Integer", "Enumeration", "Real"):
                return float(int(text)) if var.type == "Real" else int(text)
            elif kind == "Boolean" and var.type == "Boolean":
                if text not in ("true", "false", "1", "0"):
                    raise ValueError(f"not a boolean: {text!r}")
                return text in ("true", "1")
            elif kind == "String" and var.type == "String":
                return text
            else:
                self.add(where, f"an ssv:{kind} value for {var.name}, a {var.type} variable")
        except ValueError as exc:
            self.add(where, f"value {text!r}: {exc}")
        return None

    # --- experiment, annotation, sources
    def _experiment(self, el: ET.Element) -> dict:
        out = {}
        for key, attr in (("start", "startTime"), ("stop", "stopTime")):
            if el.get(attr) is not None:
                try:
                    out[key] = float(el.get(attr))
                except ValueError:
                    self.add(f"ssd:DefaultExperiment/@{attr}", f"not a number: {el.get(attr)!r}")
        for a in el.findall(f"{q('ssd:Annotations')}/{q('ssc:Annotation')}"):
            if a.get("type") != OSP_ANNOTATION:
                continue
            for alg in a.iter():
                if alg.tag.endswith("}FixedStepAlgorithm") and alg.get("baseStepSize") is not None:
                    try:
                        out["step"] = float(alg.get("baseStepSize"))
                    except ValueError:
                        self.add("ssd:DefaultExperiment//osp:FixedStepAlgorithm/@baseStepSize",
                                 f"not a number: {alg.get('baseStepSize')!r}")
        return out

    def _scene_annotation(self, el: ET.Element) -> dict:
        for a in el.findall(q("ssc:Annotation")):
            if a.get("type") != SCENE_ANNOTATION:
                continue
            text = "".join(ch.text or "" for ch in a if ch.tag.endswith("}Scene"))
            try:
                doc = tomllib.loads(text)
            except tomllib.TOMLDecodeError as exc:
                self.add(f"ssd:Annotations/ssc:Annotation[@type='{SCENE_ANNOTATION}']", f"not valid TOML: {exc}")
                return {}
            return {k: doc[k] for k in SCENE_TABLES if k in doc}
        return {}

    def _member(self, source: str, where: str, attr: str) -> str | None:
        """A relative URI inside the package as a member path, or None (with a problem)."""
        u = urlsplit(source)
        if u.scheme or u.netloc or u.query or u.fragment:
            self.add(f"{where}/@{attr}", f"{source!r}: only relative paths inside the package are supported")
            return None
        member = posixpath.normpath(unquote(u.path)) if u.path else ""
        if not member or member.startswith(("../", "/")) or member == "..":
            self.add(f"{where}/@{attr}", f"{source!r} points outside the package")
            return None
        if not (self.folder / member).is_file():
            self.add(f"{where}/@{attr}", f"{member} is not in the package")
            return None
        return member
