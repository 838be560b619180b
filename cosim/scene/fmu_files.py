"""What a run needs of an FMU file, read once per file content: its model description summary and its extracted
folder, both in the cache and keyed by the SHA-256 of the file.

Reading a model description with fmpy (XML parsed and validated against the FMI schema) costs fmpy's import and
tens of milliseconds more, for every FMU of every run; extracting an FMU to a temporary folder costs as much again.
Both depend on nothing but the bytes of the file, so

- :func:`summary` reads the model description with fmpy (``validate=True``) the first time a content is seen, checks
  the library for this machine (:mod:`tribocosim.cosim.scene.binaries`), and keeps what the scene checks and the
  master use (:class:`FmuSummary`: FMI version, GUID, model identifier, capabilities, the variables with their
  resolved unit and range, the outputs' dependencies) as JSON in ``$TRIBOCOSIM_CACHE/descriptions/``;
- :func:`extracted` unzips the FMU once into ``$TRIBOCOSIM_CACHE/extracted/`` (a temporary folder renamed into
  place, so that concurrent runs never see half an FMU), where every later run loads it from.

The file's digest is remembered by its stat signature (:mod:`tribocosim.components.native.toolchain.digests`), so a
run hashes an FMU only when it changed. A model description that cannot be read is not remembered: it is read, and
reported, again. What fmpy's model description holds beyond the summary (unit definitions, declared types) is
:attr:`tribocosim.cosim.scene.validate.FmuModel.md`, read on first use.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from tribocosim.components.native.toolchain.digests import file_sha256
from tribocosim.components.native.toolchain.library import cache_dir
from tribocosim.cosim.scene.binaries import host_platform

#: the summary's layout; a stored summary of another version is read again from the FMU
SUMMARY_VERSION = 2


class Variable:
    """A model variable as the scene checks and the master see it (fmpy's attribute names). ``unit``, ``min`` and
    ``max`` are the variable's own or else its declared type's; ``start`` is the model description's text."""

    __slots__ = ("name", "valueReference", "type", "causality", "variability", "start", "unit", "min", "max")

    def __init__(self, name: str, valueReference: int, type: str, causality: str, variability: str,  # noqa: A002
                 start: str | None = None, unit: str | None = None, min: str | None = None,  # noqa: A002
                 max: str | None = None) -> None:  # noqa: A002
        self.name, self.valueReference, self.type, self.causality = name, valueReference, type, causality
        self.variability, self.start, self.unit, self.min, self.max = variability, start, unit, min, max

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__slots__}

    def __repr__(self) -> str:
        return f"Variable({self.name!r}, {self.causality}, {self.type})"


class FmuSummary:
    """What an FMU's model description says that a run needs: its FMI version and GUID, the model identifier of its
    co-simulation interface (None: it has none), two capability flags, the variables, the outputs' direct dependencies
    (output name -> the input names, or None when not declared), ``binary_problem`` (why this machine's library in
    the FMU cannot be loaded safely, or None) and the generation tool."""

    __slots__ = ("fmi_version", "guid", "model_identifier", "can_get_and_set_fmu_state", "can_interpolate_inputs",
                 "variables", "dependencies", "binary_problem", "generation_tool")

    def __init__(self, fmi_version: str, guid: str, model_identifier: str | None, can_get_and_set_fmu_state: bool,
                 can_interpolate_inputs: bool, variables: tuple[Variable, ...], dependencies: dict,
                 binary_problem: str | None = None, generation_tool: str = "") -> None:
        self.fmi_version, self.guid, self.model_identifier = fmi_version, guid, model_identifier
        self.can_get_and_set_fmu_state, self.can_interpolate_inputs = can_get_and_set_fmu_state, can_interpolate_inputs
        self.variables, self.dependencies, self.binary_problem = variables, dependencies, binary_problem
        self.generation_tool = generation_tool

    def as_dict(self) -> dict:
        """The summary as JSON holds it (the variables as dicts)."""
        out = {k: getattr(self, k) for k in self.__slots__}
        out["variables"] = [v.as_dict() for v in self.variables]
        return out


class FmuFileError(Exception):
    """The model description of an FMU cannot be read (the message says why)."""


def _read(path: Path) -> FmuSummary:
    from fmpy import read_model_description

    from tribocosim.cosim.scene.binaries import fmu_binary_problem

    try:
        md = read_model_description(str(path), validate=True)
    except Exception as exc:  # noqa: BLE001 - fmpy raises many kinds; each is "cannot read"
        raise FmuFileError(str(exc)) from exc
    variables = []
    for v in md.modelVariables:
        dt = getattr(v, "declaredType", None)

        def own(attr):
            value = getattr(v, attr, None)
            return value if value not in (None, "") else (getattr(dt, attr, None) or None)

        variables.append(Variable(v.name, int(v.valueReference), v.type, v.causality, v.variability,
                                  None if v.start is None else str(v.start), own("unit"),
                                  None if own("min") is None else str(own("min")),
                                  None if own("max") is None else str(own("max"))))
    listed = {u.variable.name: u for u in (md.outputs or [])}
    deps = {}
    for v in md.modelVariables:
        if v.causality == "output":
            u = listed.get(v.name)
            deps[v.name] = None if u is None or u.dependencies is None else sorted(
                {d.name for d in u.dependencies if d.causality == "input"})
    cs = md.coSimulation
    problem = None
    if md.fmiVersion == "2.0" and cs is not None:
        problem = fmu_binary_problem(path, cs.modelIdentifier)
    return FmuSummary(md.fmiVersion, md.guid, cs.modelIdentifier if cs is not None else None,
                      bool(cs.canGetAndSetFMUstate) if cs is not None else False,
                      bool(cs.canInterpolateInputs) if cs is not None else False, tuple(variables), deps, problem,
                      md.generationTool or "")


def summary(path: str | Path) -> FmuSummary:
    """The summary of the FMU file ``path`` (read with fmpy once per content; FmuFileError if unreadable)."""
    path = Path(path).resolve()
    digest = file_sha256(path)
    stored = cache_dir() / "descriptions" / f"{digest[:32]}-{host_platform()}.json"
    try:
        d = json.loads(stored.read_text(encoding="utf-8"))
        if d.pop("version") == SUMMARY_VERSION:
            d["variables"] = tuple(Variable(**v) for v in d["variables"])
            return FmuSummary(**d)
    except (OSError, ValueError, KeyError, TypeError):
        pass
    found = _read(path)
    if file_sha256(path) == digest:  # not rewritten while it was read
        _write_atomically(stored, json.dumps({"version": SUMMARY_VERSION, **found.as_dict()}))
    return found


def _write_atomically(path: Path, text: str) -> None:
    from tribocosim.atomic import write_text

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, text)
    except OSError:  # a cache that cannot be written costs time, not results
        pass


def extracted(path: str | Path) -> Path:
    """The folder the FMU file ``path`` is extracted to in the cache (extracted on first use)."""
    path = Path(path).resolve()
    root = cache_dir() / "extracted"
    folder = root / file_sha256(path)[:32]
    if (folder / "modelDescription.xml").is_file():
        return folder
    import shutil
    import tempfile
    import zipfile

    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".extract-", dir=root))
    try:
        with zipfile.ZipFile(path) as z:
            z.extractall(tmp)
        try:
            os.rename(tmp, folder)
        except OSError:  # another process put it in place first (or left a broken one)
            if not (folder / "modelDescription.xml").is_file():
                shutil.rmtree(folder, ignore_errors=True)
                os.rename(tmp, folder)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return folder
