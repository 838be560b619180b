"""Build the native FMUs (FMI 2.0 or 3.0 co-simulation, C, no Python at run time) of the components.

For each component with a native implementation (``Component.native``) the build

1. generates, from the component's description, the parameter header and the FMU's variable table
   (:mod:`tribocosim.components.native.toolchain.declarations`) and the model description (FMI 2.0: this
   module, with the names, units, descriptions, start values, ranges and value references of
   the component's description; FMI 3.0: :mod:`.modeldescription3`, the same variables plus ``time`` and
   the strip's nodal-field arrays);
2. compiles the model's C sources, its glue, the FMI core (``tc_fmu_instance.c``) and the wrapper
   of the FMI version (``tc_fmi2.c`` or ``tc_fmi3.c``, against the standard's headers that fmpy
   ships) with the C compiler of the ``ziglang`` package
   (:mod:`tribocosim.components.native.toolchain.compiler`) into ``binaries/{linux64,win64,darwin64}``
   (FMI 2.0; darwin64 a universal binary, x86_64 and arm64, for Intel and Apple Silicon Macs; FMI 2.0 has no
   folder for ARM Linux) or ``binaries/{x86_64-linux,x86_64-windows,x86_64-darwin,aarch64-linux,
   aarch64-darwin}`` (FMI 3.0 platform tuples);
3. zips ``modelDescription.xml``, the binaries and the resource files (the default friction table,
   in the resource form the C code reads: ``Native.convert_resource``) into ``<ModelIdentifier>.fmu``
   (no ``.py`` file; every member with a fixed time stamp and permissions, so that two builds of the same sources
   are byte-identical), checks it with ``fmpy.validate_fmu`` and moves it into place atomically, next to a JSON
   record of its source digest and of the platforms whose binaries it holds.

The GUID (FMI 3.0: instantiation token) is derived from the source digest (C sources, generated
text, resources, compiler flags, zig version and FMI version), so a model description and a binary
of different builds do not load together. Both versions run the same C models through the same
core, so their outputs agree to the last bit.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
import zipfile
from pathlib import Path
from xml.etree.ElementTree import Element, SubElement, indent, tostring

from tribocosim.components import registry
from tribocosim.components.description import Component
from tribocosim.components.fmus import modeldescription3
from tribocosim.components.fmus.modeldescription import (INITIAL_DEPENDENCIES, OUTPUT_DEPENDENCIES, describe,
                                                         unit_definitions)
from tribocosim.components.native.toolchain import compiler, declarations, digests
from tribocosim.components.native.toolchain.library import COMMON_SOURCES
from tribocosim.atomic import replaced, write_text
from tribocosim.errors import TribocosimError

#: the sources every native FMU compiles beside its component's, per FMI version: the shared helpers, the
#: version-independent FMI core and the version's wrapper
SHARED_SOURCES = {2: (*COMMON_SOURCES, "fmi/tc_fmu_instance.c", "fmi/tc_fmi2.c"),
                  3: (*COMMON_SOURCES, "fmi/tc_fmu_instance.c", "fmi/tc_fmi3.c")}
#: the platforms a native FMU is built for (by default all): the machines it runs on
PLATFORMS = ("linux64", "win64", "darwin64", "aarch64-linux", "aarch64-darwin")
FMI_VERSIONS = (2, 3)
#: the FMI 2.0 binaries folder of each platform that has one: Apple Silicon (aarch64-darwin) runs the universal
#: darwin64 binary, and FMI 2.0 names no folder for ARM Linux
FMI2_FOLDERS = {"linux64": "linux64", "win64": "win64", "darwin64": "darwin64", "aarch64-darwin": "darwin64"}
#: the FMI 3.0 binaries folder (platform tuple) of each platform
FMI3_PLATFORMS = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "darwin64": "x86_64-darwin",
                  "aarch64-linux": "aarch64-linux", "aarch64-darwin": "aarch64-darwin"}


class FmuBuildError(TribocosimError):
    """An FMU could not be built (unknown name, compiler failure, validation problems); the message says which."""


def fmus() -> dict[str, Component]:
    """Every native FMU this installation builds: ``{model identifier: component}``."""
    return {c.model_identifier: c for c in registry.components().values() if c.native is not None}


def component(name: str) -> Component:
    known = fmus()
    if name not in known:
        raise FmuBuildError(f"unknown native FMU {name!r}; this project builds: {', '.join(known)}")
    return known[name]


def fmi2_headers() -> Path:
    """The folder of the FMI 2.0 headers (``fmi2Functions.h``...) that fmpy ships."""
    import fmpy

    folder = Path(fmpy.__file__).resolve().parent / "c-code"
    if not (folder / "fmi2Functions.h").is_file():
        raise FmuBuildError(f"the FMI 2.0 headers are not in {folder} (fmpy installation)")
    return folder


def _check_version(fmi_version: int) -> int:
    if fmi_version not in FMI_VERSIONS:
        raise FmuBuildError(f"fmi_version = {fmi_version!r} is not one of {', '.join(map(str, FMI_VERSIONS))}")
    return fmi_version


def fmi3_headers() -> Path:
    """The folder of the FMI 3.0 headers (``fmi3Functions.h``...) that fmpy ships."""
    folder = fmi2_headers()
    if not (folder / "fmi3Functions.h").is_file():
        raise FmuBuildError(f"the FMI 3.0 headers are not in {folder} (fmpy installation)")
    return folder


def sources(comp: Component, fmi_version: int = 2) -> list[Path]:
    """The C files of a component's native FMU."""
    return [compiler.source(name) for name in (*SHARED_SOURCES[_check_version(fmi_version)],
                                                     *comp.native.sources)]


def binary_path(name: str, platform: str, fmi_version: int = 2) -> str:
    """Where FMU ``name``'s library for ``platform`` (one of :data:`PLATFORMS`) is inside the FMU."""
    folders = FMI2_FOLDERS if _check_version(fmi_version) == 2 else FMI3_PLATFORMS
    if platform not in folders:
        raise FmuBuildError(f"platform {platform!r} has no FMI {fmi_version}.0 binaries folder; "
                            f"FMI {fmi_version}.0 has {', '.join(sorted(set(folders.values())))}")
    return f"binaries/{folders[platform]}/{name}{compiler.PLATFORMS[platform][1]}"


def _targets(platforms, fmi_version: int) -> dict[str, str]:
    """``{binary path's platform: toolchain platform}`` for the platforms an FMI version has folders for, each
    folder once: FMI 2.0 darwin64 is the universal binary (toolchain ``darwin64``), FMI 3.0 x86_64-darwin the
    x86_64 one; ARM Linux has no FMI 2.0 folder and is left out of an FMI 2.0 FMU."""
    out, seen = {}, set()
    for p in platforms:
        if p not in PLATFORMS:
            raise FmuBuildError(f"platform = {p!r} is not one of {', '.join(PLATFORMS)}")
        if fmi_version == 2:
            if p not in FMI2_FOLDERS or FMI2_FOLDERS[p] in seen:
                continue
            seen.add(FMI2_FOLDERS[p])
            out[FMI2_FOLDERS[p]] = FMI2_FOLDERS[p]
        else:
            out[p] = "x86_64-darwin" if p == "darwin64" else p
    return out


def description(comp: Component, fmu_guid: str, fmi_version: int = 2) -> str:
    """The model description of a component's native FMU for an FMI version."""
    if _check_version(fmi_version) == 3:
        return modeldescription3.model_description(comp, fmu_guid)
    return model_description(comp, fmu_guid)


def source_digest(name: str, fmi_version: int = 2) -> str:
    """SHA-256 over what the FMU is made of: C sources and headers, generated text, resources, flags (remembered in
    the cache while none of the files it is computed from has changed, the Python modules that generate the text and
    hold the flags and the compiler's dist-info folder included: :func:`tribocosim.components.native.toolchain.
    digests.memo`)."""
    comp = component(name)
    package = compiler.NATIVE_DIR.parent
    generators = [*Path(sys.modules[comp.build.__module__].__file__).parent.glob("*.py"), package / "description.py",
                  package / "params.py", *Path(__file__).parent.glob("*.py"),
                  *(Path(declarations.__file__).parent.glob("*.py"))]
    zig = compiler.zig_dist_info()  # its name carries the compiler's version
    files = sorted({*sources(comp, fmi_version), *compiler.headers(), *comp.resource_files, *generators,
                    *([zig] if zig is not None else [])})
    return digests.memo(digest_key(name, fmi_version), files, lambda: _source_digest(comp, fmi_version))


def digest_key(name: str, fmi_version: int = 2) -> str:
    """The key :func:`source_digest` is remembered under (:func:`tribocosim.components.native.toolchain.digests.
    remembered` finds it without this module's imports)."""
    return f"fmu {name} {fmi_version}"


def _source_digest(comp: Component, fmi_version: int) -> str:
    h = hashlib.sha256()
    for path in sorted({*sources(comp, fmi_version), *compiler.headers()}):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(declarations.params_header(comp).encode())
    h.update(declarations.model_header(comp, "").encode())
    h.update(description(comp, "", fmi_version).encode())
    for path in comp.resource_files:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(" ".join((*compiler.CFLAGS, compiler.zig_version(), *PLATFORMS)).encode())
    return h.hexdigest()


def guid(digest: str) -> str:
    """The FMU's GUID from its source digest."""
    d = digest[:32]
    return f"{{{d[:8]}-{d[8:12]}-{d[12:16]}-{d[16:20]}-{d[20:32]}}}"


def _number(x) -> str:
    return repr(float(x))


def model_description(comp: Component, fmu_guid: str) -> str:
    """The FMI 2.0 model description of a component's native FMU (variables in the declaration's order)."""
    from tribocosim import __name__ as package

    start, stop, step = comp.default_experiment
    root = Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": comp.model_identifier, "guid": fmu_guid,
        "description": comp.summary, "author": comp.author, "generationTool": f"{package} (native)",
        "variableNamingConvention": "structured", "numberOfEventIndicators": "0",
    })
    SubElement(root, "CoSimulation", {
        "modelIdentifier": comp.model_identifier, "needsExecutionTool": "false",
        "canHandleVariableCommunicationStepSize": "true", "canInterpolateInputs": "true" if comp.native.interpolates_inputs else "false",
        "maxOutputDerivativeOrder": "0", "canRunAsynchronuously": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true", "providesDirectionalDerivative": "false",
    })
    vs = declarations.variables(comp)
    root.append(unit_definitions({v["unit"] for v in vs if v["kind"] != "string"}, comp.model_identifier))
    cats = SubElement(root, "LogCategories")
    for status in ("OK", "Warning", "Discard", "Error", "Fatal"):
        SubElement(cats, "Category", {"name": f"logStatus{status}", "description": f"messages with status fmi2{status}"})
    SubElement(root, "DefaultExperiment", {"startTime": _number(start), "stopTime": _number(stop),
                                           "stepSize": _number(step)})
    mv = SubElement(root, "ModelVariables")
    outputs = []
    for vr, v in enumerate(vs):
        unit = v["unit"] if v["kind"] != "string" else ""
        attrs = {"name": v["name"], "valueReference": str(vr),
                 "description": describe(v["description"], unit) if v["kind"] != "string" else f"{v['description']} [text]",
                 "causality": v["causality"]}
        if v["causality"] == "parameter":
            attrs["variability"] = "fixed"
        elif v["causality"] == "input":
            attrs["variability"] = "continuous"
        else:
            attrs["variability"] = "discrete" if v["kind"] == "integer" else "continuous"
            attrs["initial"] = "calculated"
            outputs.append(vr + 1)
        sv = SubElement(mv, "ScalarVariable", attrs)
        if v["kind"] == "string":
            SubElement(sv, "String", {"start": str(v["start"])})
            continue
        typed = {} if v["causality"] == "output" else {  # calculated: no start value (FMI 2.0 section 2.2.7)
            "start": str(int(v["start"])) if v["kind"] == "integer" else _number(v["start"])}
        if v["kind"] == "real":
            typed["unit"] = unit
        if v["low"] is not None:
            typed["min"] = str(int(v["low"])) if v["kind"] == "integer" else _number(v["low"])
        if v["high"] is not None:
            typed["max"] = str(int(v["high"])) if v["kind"] == "integer" else _number(v["high"])
        SubElement(sv, "Integer" if v["kind"] == "integer" else "Real", typed)
    structure = SubElement(root, "ModelStructure")
    if outputs:
        out = SubElement(structure, "Outputs")
        for index in outputs:
            SubElement(out, "Unknown", {"index": str(index), "dependencies": OUTPUT_DEPENDENCIES})
        initial = SubElement(structure, "InitialUnknowns")
        for index in outputs:
            deps = declarations.initial_dependencies(vs, vs[index - 1], 1) or INITIAL_DEPENDENCIES
            SubElement(initial, "Unknown", {"index": str(index), "dependencies": deps})
    indent(root, "  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"


def compile_binaries(name: str, folder: str | os.PathLike, platforms=PLATFORMS, digest: str | None = None,
                     fmi_version: int = 2, progress=None) -> dict:
    """Generate the headers of FMU ``name`` into ``folder/include`` and compile its binaries into
    ``folder/`` at their places in the FMU (:func:`binary_path`); returns ``{platform: library path}``.
    ``progress(platform)`` is called before each platform's compile."""
    comp = component(name)
    folder = Path(folder)
    include = folder / "include"
    include.mkdir(parents=True, exist_ok=True)
    declarations.write_params_headers(include, [comp])
    (include / "tc_fmu_model.h").write_text(
        declarations.model_header(comp, guid(digest or source_digest(name, fmi_version))), encoding="ascii")
    if fmi_version == 2:
        headers = {"include_dirs": [include, fmi2_headers()]}
    else:  # fmi3FunctionTypes.h declares callbacks without prototypes: system headers, exempt from -Werror
        headers = {"include_dirs": [include], "extra_flags": ["-isystem", str(fmi3_headers())]}
    built = {}
    for platform, target in _targets(platforms, fmi_version).items():
        out = folder / binary_path(name, platform, fmi_version)
        if progress is not None:
            progress(platform)
        try:
            built[platform] = compiler.compile_shared(sources(comp, fmi_version), out, target, **headers)
        except compiler.CompileError as exc:
            raise FmuBuildError(f"FMU {name}: {exc}") from exc
    return built


def build_native_fmus(out_dir: str | os.PathLike, names=None, platforms=PLATFORMS,
                      fmi_version: int = 2, progress=None) -> dict[str, Path]:
    """Build native FMUs into ``out_dir`` and return ``{name: path to .fmu}`` (see the module docstring).

    ``fmi_version`` 2 or 3; the file names are the same (``<ModelIdentifier>.fmu``), so FMUs of the two
    versions go to different folders. ``progress(line)``, if given, receives one line before each compile (the FMU,
    the FMI version, the platform, its number among all) and before each validation.

    Raises
    ------
    FmuBuildError
        Naming the FMU and the cause (missing resource, compiler output, validation problems).
    """
    _check_version(fmi_version)
    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    selected = list(fmus()) if names is None else list(names)
    for name in selected:  # every FMU's resources, before building any of them
        for path in component(name).resource_files:
            if not path.is_file():
                raise FmuBuildError(f"FMU {name}: required file {path} is missing")
    total = len(selected) * len(_targets(platforms, fmi_version))
    done = iter(range(1, total + 1))

    def line(name: str):
        if progress is None:
            return None
        return lambda platform: progress(f"compiling {name} (FMI {fmi_version}.0) for {platform} "
                                         f"({next(done)}/{total})")

    return {name: _build_one(name, out, tuple(platforms), fmi_version, line(name), progress) for name in selected}


#: the time stamp of every member of a native FMU's zip: a fixed one (the earliest a zip can hold), so that two builds
#: of the same sources give the same bytes
ZIP_TIME = (1980, 1, 1, 0, 0, 0)


def _member(z: zipfile.ZipFile, name: str, data: bytes) -> None:
    """Write one member with the fixed time stamp and permissions (rw-r--r--, a folder rwxr-xr-x)."""
    info = zipfile.ZipInfo(name, date_time=ZIP_TIME)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = (0o40755 if name.endswith("/") else 0o100644) << 16
    info.create_system = 3  # Unix, whatever the building machine: the permissions above are Unix ones
    z.writestr(info, data)


def _build_one(name: str, out: Path, platforms, fmi_version: int, compiling=None, progress=None) -> Path:
    comp = component(name)
    digest = source_digest(name, fmi_version)
    targets = _targets(platforms, fmi_version)
    target = out / f"{name}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"tribocosim-native-{name}-") as tmp, replaced(target, ".fmu") as partial:
        stage = Path(tmp)
        compile_binaries(name, stage, platforms, digest, fmi_version, compiling)
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            _member(z, "modelDescription.xml", description(comp, guid(digest), fmi_version).encode("utf-8"))
            for platform in targets:
                inside = binary_path(name, platform, fmi_version)
                _member(z, inside, (stage / inside).read_bytes())
            for path in comp.resource_files:
                if comp.native.convert_resource is not None:  # the form the C code reads
                    path = comp.native.convert_resource(path, stage)
                _member(z, f"resources/{path.name}", path.read_bytes())
            if not comp.resource_files:
                _member(z, "resources/", b"")
        if progress is not None:
            progress(f"validating {name}.fmu (fmpy validate)")
        _validate(name, partial)  # the FMU replaces the one at its name only when it passes
    # the platforms whose binaries the zip holds (FMI 2.0 has no ARM Linux folder, and darwin64 serves both Macs)
    record = {"name": name, "variant": "native", "fmi_version": fmi_version, "source_digest": digest,
              "platforms": sorted(targets), "python": sys.version.split()[0], "ziglang": compiler.zig_version()}
    write_text(out / f"{name}.fmu.json", json.dumps(record, indent=2) + "\n")
    return target


__all__ = ["binary_path", "build_native_fmus", "compile_binaries", "description", "fmi3_headers", "fmus",
           "model_description", "source_digest"]


def _validate(name: str, fmu: Path) -> None:
    """``fmpy validate`` the built FMU: FmuBuildError with its problems."""
    from fmpy.validation import validate_fmu

    problems = validate_fmu(str(fmu))
    if problems:
        raise FmuBuildError(f"FMU {name}: fmpy validate found problems:\n" + "\n".join(problems))
