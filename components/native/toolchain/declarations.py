"""The C declarations of a component, generated from its description (so that C and Python cannot drift).

Two headers, written into a build folder next to the sources:

``<prefix>_params.h`` (one per component with a native implementation)
    ``typedef struct <prefix>_params {...}``: one member per field of the component's parameter
    dataclass, same names, same order; float fields are ``double``, integer fields ``int``, fields
    with choices ``int`` (the index into the choices tuple, named ``<PREFIX>_<FIELD>_<CHOICE>``),
    text fields ``const char *``; before it, ``#define <PREFIX>_<NAME> value`` of each of the component's
    ``Native.constants`` (numbers defined once in Python). The native model is written against it. And
    ``<prefix>_params_check(p, msg)``: every float field finite and within its declared range (both bounds
    inclusive, a value within ``TC_BOUND_RTOL`` of a bound on it, as
    :func:`tribocosim.components.params.within_bounds`),
    every integer field within its range, every choice an index of its choices; ``TC_ERROR`` naming the first field
    that is not, its value and what is allowed. The model's create function calls it, so the ranges the C side
    checks are the declared ones.
``tc_fmu_model.h`` (one per FMU)
    the model identifier and GUID, the table of FMU variables (:data:`tc_variable` of ``tc_fmu.h``:
    the parameters, then the inputs, then the outputs, in the order and with the names, units,
    start values, ranges and choices of the model description), ``TC_P_<name>`` indices of the
    parameters, and ``<prefix>_fill_params(values, p)`` that fills the model's struct from the
    FMU's parameter values; ``TC_BOUNDS``, the ranges the outputs and inputs are built for (:func:`port_bounds`);
    for FMI 3.0 the value references of the variables only it has
    (:func:`fmi3_variables`: ``TC_VR_TIME``, and with array outputs ``TC_N_ARRAYS``, ``TC_ARRAYS``,
    ``TC_A_<name>``, ``TC_VR_ARRAY_SIZE``, ``TC_VR_ARRAYS``). The generic FMI wrappers
    (``tc_fmi2.c``, ``tc_fmi3.c``, their core ``tc_fmu_instance.c``) and the component's glue
    (``tc_<name>_fmu.c``) include it.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

from tribocosim.components.description import Component
from tribocosim.components.params import bound_text
from tribocosim.errors import TribocosimError


def _c_string(text: str) -> str:
    """A C string literal (ASCII; quotes, backslashes and control characters escaped)."""
    return json.dumps(text, ensure_ascii=True)


def _c_double(x) -> str:
    """A C double literal that reads back as the same float (Python repr; inf as HUGE_VAL)."""
    x = float(x)
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "-HUGE_VAL"
    text = repr(x)
    return text if any(ch in text for ch in ".en") else text + ".0"


def _kind(f: dataclasses.Field) -> str:
    meta = f.metadata
    if meta.get("text") or "choices" in meta:
        return "string"
    return "integer" if meta.get("integer") else "real"


def _check_lines(comp: Component) -> list[str]:
    """The statements of ``<prefix>_params_check`` (see the module docstring), one check per field."""
    lines = []
    for f in dataclasses.fields(comp.parameters):
        meta, name = f.metadata, f.name
        unit = meta.get("unit") if meta.get("unit") not in (None, "", "1") else ""
        sp = " " if unit else ""
        if "choices" in meta:
            choices = meta["choices"]
            allowed = ", ".join(f"{k} ({c})" for k, c in enumerate(choices))
            lines += [f"    if (p->{name} < 0 || p->{name} > {len(choices) - 1})",
                      f"        return tc_fail(msg, TC_ERROR, \"{name} = %d is not allowed; choose one of {allowed}\", "
                      f"p->{name});"]
        elif meta.get("text"):
            continue
        elif meta.get("integer"):
            low, high = meta.get("low"), meta.get("high")
            tests = ([f"p->{name} < {int(low)}"] if low is not None else []) + \
                    ([f"p->{name} > {int(high)}"] if high is not None else [])
            if tests:
                lo = str(int(low)) if low is not None else "-inf"
                hi = str(int(high)) if high is not None else "inf"
                lines += [f"    if ({' || '.join(tests)})",
                          f"        return tc_fail(msg, TC_ERROR, \"{name} = %d is out of range; allowed: "
                          f"{'[' if low is not None else '('}{lo}, {hi}{']' if high is not None else ')'}\", "
                          f"p->{name});"]
        else:
            low, high = meta.get("low"), meta.get("high")
            tests = [f"!isfinite(p->{name})"]
            tests += [f"tc_below(p->{name}, {_c_double(low)})"] if low is not None else []
            tests += [f"tc_above(p->{name}, {_c_double(high)})"] if high is not None else []
            lo = bound_text(low) if low is not None else "-inf"
            hi = bound_text(high) if high is not None else "inf"
            lines += [f"    if ({' || '.join(tests)})",
                      f"        return tc_fail(msg, TC_ERROR, \"{name} = %s{sp}{unit} is out of range; allowed: "
                      f"{'[' if low is not None else '('}{lo}, {hi}{']' if high is not None else ')'}{sp}{unit}\", "
                      f"tc_repr_double(p->{name}, r));"]
    return lines


def params_header(comp: Component) -> str:
    """The ``<prefix>_params.h`` of a component (see the module docstring)."""
    prefix = comp.native.prefix
    guard = f"{prefix.upper()}_PARAMS_H"
    lines = [
        f"/* Parameters of the {comp.name} model: one member per field of {comp.parameters.__name__}, same names and",
        " * order. GENERATED from the component's description by tribocosim/components/native/toolchain/declarations.py:",
        " * do not edit. float fields are double, integer fields int, choice fields int (the index of the value",
        f" * among its choices, named {prefix.upper()}_<FIELD>_<CHOICE>), text fields const char *. SI units. */",
        f"#ifndef {guard}",
        f"#define {guard}",
        "",
        "#include <math.h>",
        "",
        '#include "tc_common.h"',
        "",
    ]
    for name, value, what in comp.native.constants:
        lines.append(f"#define {prefix.upper()}_{name.upper()} {_c_double(value)} /* {what.replace('*/', '* /')} */")
    if comp.native.constants:
        lines.append("")
    for f in dataclasses.fields(comp.parameters):
        for k, choice in enumerate(f.metadata.get("choices", ())):
            lines.append(f"#define {prefix.upper()}_{f.name.upper()}_{choice.upper()} {k}")
        if "choices" in f.metadata:
            lines.append("")
    lines.append(f"typedef struct {prefix}_params {{")
    for f in dataclasses.fields(comp.parameters):
        meta = f.metadata
        ctype = {"real": "double", "integer": "int"}.get(_kind(f), "int" if "choices" in meta else "const char *")
        unit = f" [{meta['unit']}]" if meta.get("unit") else ""
        lines.append(f"    {ctype} {f.name}; /* {meta['description'].replace('*/', '* /')}{unit} */")
    lines += [f"}} {prefix}_params;", ""]
    lines += ["/* Every field of p against its declaration: a float finite and within its range (both bounds inclusive, "
              "a value",
              " * within TC_BOUND_RTOL of a bound on it), an integer within its range, a choice an index of its choices. "
              "TC_ERROR",
              " * naming the first field that is not, its value and what is allowed. */",
              f"static inline int {prefix}_params_check(const {prefix}_params *p, tc_msg msg) {{",
              "    char r[TC_REPR_SIZE];", "    (void)r;"]
    lines += _check_lines(comp)
    lines += ["    return TC_OK;", "}", "", "#endif", ""]
    return "\n".join(lines)


def variables(comp: Component) -> list[dict]:
    """The FMU's variables in model-description order: name, kind, causality, index, unit, start, range,
    choices, description (value reference = position)."""
    out = []
    for k, f in enumerate(comp.parameter_fields):
        meta = f.metadata
        kind = _kind(f)
        out.append({
            "name": f.name, "kind": kind, "causality": "parameter", "index": k,
            "unit": "" if kind == "string" else (meta.get("unit") or "1"),
            "start": f.default, "low": meta.get("low"), "high": meta.get("high"),
            "choices": tuple(meta.get("choices", ())),
            "description": meta["description"],
        })
    for k, port in enumerate(comp.inputs):
        out.append({"name": port.name, "kind": "real", "causality": "input", "index": k, "unit": port.unit or "1",
                    "start": port.start, "low": None, "high": None, "choices": (),
                    "description": port.description})
    inputs = [port.name for port in comp.inputs]
    for k, port in enumerate(comp.outputs):
        unknown = sorted(set(port.initial_inputs) - set(inputs))
        if unknown:
            raise TribocosimError(f"component {comp.name}: output {port.name} names initial_inputs {unknown} that are "
                                  f"not inputs; inputs: {inputs}")
        out.append({"name": port.name, "kind": "integer" if port.integer else "real", "causality": "output",
                    "index": k, "unit": port.unit or "1", "start": port.start, "low": None, "high": None,
                    "choices": (), "description": port.description, "initial_inputs": tuple(port.initial_inputs)})
    return out


def initial_dependencies(vs: list[dict], output: dict, base: int) -> str:
    """The InitialUnknown dependencies of ``output`` among the variables ``vs`` (model-description order): their
    positions + ``base`` (FMI 2.0: 1-based indices, base 1; FMI 3.0: value references, base 0), space-separated."""
    names = set(output.get("initial_inputs", ()))
    return " ".join(str(k + base) for k, v in enumerate(vs) if v["causality"] == "input" and v["name"] in names)


def port_bounds(comp: Component) -> list[dict]:
    """The ranges the component's outputs and inputs are built for (``Port.low``/``high``): per bound the port's
    index among the outputs (or the inputs: ``input`` 1), the side (-1 low, +1 high), the value or the index of the
    parameter that holds it (-1: the value), and why. The native FMU warns when an output leaves one after a step, or
    a step takes an input outside one (tc_fmu_instance.c)."""
    index = {v["name"]: v["index"] for v in variables(comp) if v["causality"] == "parameter"}
    out = []
    for is_input, ports in ((0, comp.outputs), (1, comp.inputs)):
        for k, port in enumerate(ports):
            for side, bound in ((-1, port.low), (+1, port.high)):
                if bound is None:
                    continue
                if isinstance(bound, str) and bound not in index:
                    raise TribocosimError(f"component {comp.name}: the bound {bound!r} of {port.name} is not a "
                                          "parameter")
                out.append({"output": k, "name": port.name, "side": side,
                            "value": 0.0 if isinstance(bound, str) else float(bound),
                            "parameter": index[bound] if isinstance(bound, str) else -1,
                            "bound": bound if isinstance(bound, str) else repr(float(bound)),
                            "why": port.why or port.description, "input": is_input})
    return out


def fmi3_variables(comp: Component) -> list[dict]:
    """The variables only the FMI 3.0 FMU has, numbered on after :func:`variables` (``vr``): the
    independent variable ``time``, and for a component with array outputs (``Native.arrays``) the
    UInt64 structural parameter of their length, then the arrays (``dimension``: that parameter's
    value reference). The parameter the length derives from is ``structural_parameter``."""
    vr = len(variables(comp))
    out = [{"name": "time", "kind": "real", "causality": "independent", "vr": vr, "unit": "s",
            "description": "simulation time"}]
    native = comp.native
    if native is None or not native.arrays:
        return out
    size = native.array_size
    fields = {f.name: f for f in comp.parameter_fields}
    if size is None or size.parameter not in fields or _kind(fields[size.parameter]) != "integer":
        raise TribocosimError(f"component {comp.name}: array outputs need an array_size derived from an integer "
                              "parameter")
    meta = fields[size.parameter].metadata
    shift = lambda x: None if x is None else int(x) + size.offset  # noqa: E731
    out.append({"name": size.name, "kind": "uint64", "causality": "structuralParameter", "vr": vr + 1, "unit": "",
                "start": shift(fields[size.parameter].default), "low": shift(meta.get("low")),
                "high": shift(meta.get("high")), "description": size.description,
                "structural_parameter": size.parameter, "offset": size.offset})
    for k, port in enumerate(native.arrays):
        out.append({"name": port.name, "kind": "real", "causality": "output", "vr": vr + 2 + k,
                    "unit": port.unit or "1", "description": port.description, "dimension": vr + 1})
    return out


def _fmi3_lines(comp: Component) -> list[str]:
    """The FMI 3.0 value references of ``tc_fmu_model.h``."""
    extra = fmi3_variables(comp)
    arrays = [v for v in extra if "dimension" in v]
    lines = ["/* FMI 3.0 only (tc_fmi3.c): value references after the FMI 2.0 variables */",
             f"#define TC_VR_TIME {extra[0]['vr']}", f"#define TC_N_ARRAYS {len(arrays)}"]
    if arrays:
        size = extra[1]
        index = {v["name"]: v["index"] for v in variables(comp) if v["causality"] == "parameter"}
        lines += [f"#define TC_VR_ARRAY_SIZE {size['vr']} /* {size['name']}: UInt64 structural parameter */",
                  f"#define TC_ARRAY_SIZE_NAME {_c_string(size['name'])}",
                  f"#define TC_ARRAY_SIZE_PARAMETER {index[size['structural_parameter']]} "
                  f"/* {size['name']} = {size['structural_parameter']} + TC_ARRAY_SIZE_OFFSET */",
                  f"#define TC_ARRAY_SIZE_OFFSET {size['offset']}",
                  f"#define TC_VR_ARRAYS {arrays[0]['vr']} /* array k: TC_VR_ARRAYS + k */"]
        lines += [f"#define TC_A_{v['name']} {k}" for k, v in enumerate(arrays)]
        lines.append(f"static const char *const TC_ARRAYS[TC_N_ARRAYS] = "
                     f"{{{', '.join(_c_string(v['name']) for v in arrays)}}};")
    return lines + [""]


def model_header(comp: Component, guid: str) -> str:
    """The ``tc_fmu_model.h`` of a component's FMU (see the module docstring)."""
    prefix = comp.native.prefix
    vs = variables(comp)
    n_par = sum(v["causality"] == "parameter" for v in vs)
    lines = [
        f"/* The {comp.model_identifier} FMU's variables and parameter struct filler. GENERATED from the component's",
        " * description by tribocosim/components/native/toolchain/declarations.py: do not edit. */",
        "#ifndef TC_FMU_MODEL_H",
        "#define TC_FMU_MODEL_H",
        "",
        "#include <math.h>",
        "",
        '#include "tc_fmu.h"',
        f'#include "{comp.native.params_header}"',
        "",
        f"#define TC_MODEL_IDENTIFIER {_c_string(comp.model_identifier)}",
        f"#define TC_GUID {_c_string(guid)}",
        f"#define TC_N_PARAMETERS {n_par}",
        f"#define TC_N_INPUTS {len(comp.inputs)}",
        f"#define TC_N_OUTPUTS {len(comp.outputs)}",
        f"#define TC_N_VARIABLES {len(vs)}",
        f"#define TC_CAN_INTERPOLATE_INPUTS {int(comp.native.interpolates_inputs)}",
        "",
    ]
    for v in vs:
        if v["causality"] == "parameter":
            lines.append(f"#define TC_P_{v['name']} {v['index']}")
    lines.append("")
    for v in vs:
        if v["choices"]:
            items = ", ".join(_c_string(c) for c in v["choices"])
            lines.append(f"static const char *const TC_CHOICES_{v['name']}[] = {{{items}}};")
    lines += ["", "static const tc_variable TC_VARIABLES[TC_N_VARIABLES] = {"]
    kinds = {"real": "TC_KIND_REAL", "integer": "TC_KIND_INTEGER", "string": "TC_KIND_STRING"}
    causes = {"parameter": "TC_CAUSALITY_PARAMETER", "input": "TC_CAUSALITY_INPUT", "output": "TC_CAUSALITY_OUTPUT"}
    for v in vs:
        text = v["kind"] == "string"
        start = "0.0" if text else _c_double(v["start"])
        start_text = _c_string(str(v["start"])) if text else "NULL"
        low, high = v["low"], v["high"]
        choices = (f"TC_CHOICES_{v['name']}", len(v["choices"])) if v["choices"] else ("NULL", 0)
        lines.append(
            f"    {{{_c_string(v['name'])}, {kinds[v['kind']]}, {causes[v['causality']]}, {v['index']}, "
            f"{_c_string(v['unit'] if not text else '')}, {start}, {start_text}, {int(low is not None)}, "
            f"{int(high is not None)}, {_c_double(low if low is not None else 0)}, "
            f"{_c_double(high if high is not None else 0)}, {choices[0]}, {choices[1]}}},")
    lines += ["};", ""]
    bounds = port_bounds(comp)
    lines += ["/* the ranges the outputs and inputs are built for (output or input index, side -1 low / +1 high, value,",
              " * parameter index or -1 for the value, why, 1 for an input): an output outside one after a step, or an",
              " * input outside one in an accepted step, is a warning */",
              f"#define TC_N_BOUNDS {len(bounds)}",
              "static const tc_bound TC_BOUNDS[TC_N_BOUNDS > 0 ? TC_N_BOUNDS : 1] = {"]
    lines += [f"    {{{b['output']}, {b['side']}, {_c_double(b['value'])}, {b['parameter']}, {_c_string(b['bound'])}, "
              f"{_c_string(b['why'])}, {b['input']}}}," for b in bounds] or ["    {0, 0, 0.0, -1, \"\", \"\", 0},"]
    lines += ["};", ""]
    lines += _fmi3_lines(comp)
    lines += [f"/* {comp.parameters.__name__} from the FMU's parameter values (choices by index) */",
              f"static inline void {prefix}_fill_params(const tc_param_value *v, {prefix}_params *p) {{"]
    index = {v["name"]: v["index"] for v in vs if v["causality"] == "parameter"}
    for f in dataclasses.fields(comp.parameters):
        k = index[f.name]
        meta = f.metadata
        if "choices" in meta:
            lines.append(f"    p->{f.name} = v[{k}].choice;")
        elif meta.get("text"):
            lines.append(f"    p->{f.name} = v[{k}].text;")
        elif meta.get("integer"):
            lines.append(f"    p->{f.name} = (int)v[{k}].number;")
        else:
            lines.append(f"    p->{f.name} = v[{k}].number;")
    lines += ["}", "", "#endif", ""]
    return "\n".join(lines)


def write_params_headers(folder: str | Path, components) -> list[Path]:
    """Write the ``<prefix>_params.h`` of every component with a native implementation into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for comp in components:
        if comp.native is not None:
            path = folder / comp.native.params_header
            path.write_text(params_header(comp), encoding="ascii")
            written.append(path)
    return written
