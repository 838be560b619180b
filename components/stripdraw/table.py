"""The friction table format: mu(P, v, beta) on a rectilinear grid, in one ``.npz`` file.

This module is the only owner of the format: the surrogate writes tables through
:func:`write_table`, the strip-draw model and its FMU read them through :func:`read_table`; lookups go through the
native core (``components/native/core/tc_table_lookup.c``, the code the FMU runs; :class:`NativeTable`).

File layout (numpy ``.npz``, read with ``allow_pickle=False``):

=========================  =============================  ===========================================
key                        shape / type                   meaning
=========================  =============================  ===========================================
``pressure``               (nP,) float64, increasing      contact pressure axis P [Pa]
``velocity``               (nv,) float64, increasing      sliding-velocity axis v [m/s] (magnitude, >= 0)
``beta``                   (nb,) float64, increasing      debris area-fraction axis beta [-]
``mu``                     (nP, nv, nb) float64, >= 0     friction coefficient mu(P, v, beta) [-]
``contact_area``           (nP, nv, nb) float64, >= 0     version 2: ensemble mean of A_c/A0 [-]
``particle_area``          (nP, nv, nb) float64, >= 0     version 2: ensemble mean of A_p/A0 [-]
``contact_area_std``       (nP, nv, nb) float64, >= 0     version 2: member std of A_c/A0 [-]
``particle_area_std``      (nP, nv, nb) float64, >= 0     version 2: member std of A_p/A0 [-]
``simulated``              (nP, nv, nb) float64, 0 or 1   version 3: 1 where slides were run at the node
``contact_area_se``        (nP, nv, nb) float64, >= 0     version 3: standard error of ``contact_area``
``particle_area_se``       (nP, nv, nb) float64, >= 0     version 3: standard error of ``particle_area``
``particle_area_clusters`` (nP, nv, nb) float64, >= 0     version 3: A_p/A0 of the paper's cluster rule alone
``particle_area_clusters_se`` (nP, nv, nb) float64, >= 0  version 3: its standard error
``mu_se``                  (nP, nv, nb) float64, >= 0     version 4: standard error of ``mu``
``metadata``               0-d str (JSON object)          see below
=========================  =============================  ===========================================

Version 2 carries the contact areas behind mu, so that the strip-draw model can compute
mu = mu0 (1 - A_p / A_c) with either contact-area convention (docs/model.md section 4); version 3 adds
where the values were simulated (a lookup that reads another node is counted, docs/model.md section 4), the
standard errors of the tabulated areas, and the flake-borne area of the paper's blocking rule alone (Fig. 8) beside
that of every load-bearing flake. Version 4 holds, at every simulated node, the ensemble means of the slides with
their ensemble standard errors (``mu_se`` added: that of mu = mu0 (1 - A_p / A_c) from the members' A_p and A_c),
and is interpolated monotone cubic (below). Versions 1 to 3 stay readable and are read as before (multilinear).
``metadata`` always holds ``format`` (``"tribocosim-friction-table"``), ``format_version`` (1 to 4), ``units``
(array -> unit), ``provenance`` (``"closed_form"`` or ``"mesoscale"``), ``beta_threshold`` (the cap of beta, Eq. 24)
and ``content_hash``: the SHA-256 of the axes and arrays (float64, little-endian, C order) and of the canonical JSON
of the other metadata. A file whose hash or format version does not match is refused.

The native code reads the table in its resource form (:func:`write_table_resource`): an array file
(:mod:`tribocosim.components.native.resource_io.array_file`) with the axes, the value arrays, ``format_version``,
``beta_threshold``, ``content_hash``, ``provenance`` and ``source_sha256`` (the SHA-256 of the bytes of the ``.npz``
it was written from), written from a verified table (the FMU build bundles it as ``friction_table.tca``; a table
file ``X.npz`` has its resource at ``X.tca``). The native reader refuses ``X.tca`` when ``X.npz`` exists and its
SHA-256 is not the recorded one: a table replaced after its resource was written is never served from the old
resource.

Interpolation (``tc_table_lookup.c`` states the equations): versions 1 to 3 multilinear in (P, v, beta); version 4
monotone cubic (Fritsch-Butland PCHIP, the slopes of a node from its neighbours of the same kind, simulated or
not) in ln P, then in beta, and linear in v; every version reproduces the nodes exactly. The strip-draw law
interpolates what mu is linear in (docs/model.md section 4). A lookup reads the corners of its cell whose weight
(the product of the local coordinates, in ln P on a version 4 pressure axis) exceeds ``READ_WEIGHT`` (1e-9); a
lookup that reads an unsimulated node or is outside an axis is flagged (clamped). Queries outside the axes follow a
policy: ``"clamp"`` (evaluate at the nearest edge and flag them, so the caller can count them) or ``"error"``
(raise :class:`~tribocosim.errors.TableDomainError`). A query within ``AXIS_END_TOLERANCE`` (1e-9, relative) of an
axis end is on the end.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import ctypes
import functools

import numpy as np

from tribocosim.components.params import BOUND_RTOL
from tribocosim.errors import ParameterError, TableDomainError, TableError

FORMAT = "tribocosim-friction-table"
FORMAT_VERSION = 4  # written when the table carries the version 4 arrays; 1 to 3 are still read and written
VERSIONS = (1, 2, 3, 4)
AXES = ("pressure", "velocity", "beta")
#: a query within this of an axis end (relative to the end) is on the end, not outside the table: the round-off of
#: the inputs (a press holding a set-point equal to the last pressure delivers it to within 1e-15 on either side;
#: 12250 N on the 35 x 35 mm pad is 9999999.999999998 Pa); the bound tolerance of every declared range
#: (components/params.py), and the native lookup's (TC_TABLE_AXIS_END_TOLERANCE of tc_table.h)
AXIS_END_TOLERANCE = BOUND_RTOL
AREAS = ("contact_area", "particle_area", "contact_area_std", "particle_area_std")
#: the version 3 arrays (all of them, or none)
EXTRAS = ("simulated", "contact_area_se", "particle_area_se", "particle_area_clusters", "particle_area_clusters_se")
#: the arrays version 4 adds to version 3's
EXTRAS_4 = ("mu_se",)
UNITS = {"pressure": "Pa", "velocity": "m/s", "beta": "1", "mu": "1",
         **{a: "1" for a in (*AREAS, *EXTRAS, *EXTRAS_4)}}
#: a lookup reads a node when its weight exceeds this (relative: the weights of a lookup sum to 1; tc_table_lookup.h)
READ_WEIGHT = 1e-9
#: the longest beta axis a version 4 table may have (TC_TABLE_BETA_MAX of tc_table.h)
BETA_MAX_4 = 64


def _as_axis(name: str, values) -> np.ndarray:
    a = np.ascontiguousarray(values, dtype=np.float64)
    if a.ndim != 1 or a.size < 1:
        raise ParameterError(f"table axis {name} must be a non-empty 1-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"table axis {name} has non-finite values")
    if a.size > 1 and not np.all(np.diff(a) > 0):
        raise ParameterError(f"table axis {name} must be strictly increasing")
    if name != "pressure" and a[0] < 0:
        raise ParameterError(f"table axis {name} starts at {a[0]!r}; it must be >= 0")
    return a


@dataclass(frozen=True)
class FrictionTable:
    """A friction table mu(P, v, beta) with its metadata.

    Parameters
    ----------
    pressure, velocity, beta : array_like
        Strictly increasing axes [Pa], [m/s], [-].
    mu : array_like
        Friction coefficients, shape ``(len(pressure), len(velocity), len(beta))``.
    metadata : dict
        Free-form JSON-serialisable metadata; ``beta_threshold`` is required.
    contact_area, particle_area, contact_area_std, particle_area_std : array_like, optional
        Version 2: the ensemble means of A_c/A0 and A_p/A0 and their member standard deviations,
        same shape as ``mu`` (all four, or none).
    extras : dict, optional
        Version 3 (with the version 2 areas): every array of :data:`EXTRAS` by name, same shape as ``mu``;
        version 4: those and :data:`EXTRAS_4`.
    """

    pressure: np.ndarray
    velocity: np.ndarray
    beta: np.ndarray
    mu: np.ndarray
    metadata: dict = field(default_factory=dict)
    contact_area: np.ndarray | None = None
    particle_area: np.ndarray | None = None
    contact_area_std: np.ndarray | None = None
    particle_area_std: np.ndarray | None = None
    extras: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in AXES:
            object.__setattr__(self, name, _as_axis(name, getattr(self, name)))
        shape = (self.pressure.size, self.velocity.size, self.beta.size)
        given = [a for a in AREAS if getattr(self, a) is not None]
        if given and len(given) != len(AREAS):
            raise ParameterError(f"table areas: {given} given; a version 2 table needs all of {list(AREAS)}")
        extras = dict(self.extras or {})
        if extras and (sorted(extras) not in (sorted(EXTRAS), sorted(EXTRAS + EXTRAS_4)) or not given):
            raise ParameterError(f"table extras: {sorted(extras)} given; a version 3 table needs the version 2 "
                                 f"areas and all of {list(EXTRAS)}, a version 4 table also {list(EXTRAS_4)}")
        for name in ("mu", *given, *extras):
            arr = np.ascontiguousarray(extras[name] if name in extras else getattr(self, name), dtype=np.float64)
            if arr.shape != shape:
                raise ParameterError(f"table {name} has shape {arr.shape}; the axes need {shape}")
            if not np.all(np.isfinite(arr)) or np.any(arr < 0):
                raise ParameterError(f"table {name} must be finite and >= 0 everywhere")
            if name in extras:
                extras[name] = arr
            else:
                object.__setattr__(self, name, arr)
        if extras and not np.all((extras["simulated"] == 0) | (extras["simulated"] == 1)):
            raise ParameterError("table simulated must be 0 or 1 at every node")
        object.__setattr__(self, "extras", extras)
        if self.version == 4 and not (self.pressure[0] > 0 and self.beta.size <= BETA_MAX_4):
            raise ParameterError(f"a version 4 table interpolates in ln P on at most {BETA_MAX_4} beta nodes; this "
                                 f"one's pressure axis starts at {self.pressure[0]!r} Pa and it has {self.beta.size} "
                                 "beta nodes")
        bt = self.metadata.get("beta_threshold")
        if bt is None or not (0 < float(bt) <= 1):
            raise ParameterError(f"table metadata beta_threshold = {bt!r}; a value in (0, 1] is required")
        object.__setattr__(self, "metadata", dict(self.metadata))

    @property
    def version(self) -> int:
        """The format version: 4 with the version 4 arrays, 3 with the version 3 arrays, 2 with the areas, else 1."""
        if self.extras:
            return 4 if EXTRAS_4[0] in self.extras else 3
        return 2 if self.contact_area is not None else 1

    def arrays(self) -> tuple[str, ...]:
        """The names of the value arrays this table holds (``mu``, the areas in version 2, the extras in 3 and 4)."""
        return ("mu", *AREAS, *EXTRAS, *EXTRAS_4)[: {1: 1, 2: 1 + len(AREAS), 3: 1 + len(AREAS) + len(EXTRAS),
                                                      4: 1 + len(AREAS) + len(EXTRAS) + len(EXTRAS_4)}[self.version]]

    def array(self, name: str) -> np.ndarray:
        """One of :meth:`arrays` by name."""
        if name in self.extras:
            return self.extras[name]
        if name not in self.arrays():
            raise ParameterError(f"table array {name!r} is not in this version {self.version} table; "
                                 f"it holds {list(self.arrays())}")
        return getattr(self, name)

    @property
    def beta_threshold(self) -> float:
        """Cap of the debris fraction beta recorded with the table (Eq. 24)."""
        return float(self.metadata["beta_threshold"])

    @property
    def provenance(self) -> str:
        """Where the values come from (``closed_form`` or ``mesoscale``)."""
        return str(self.metadata.get("provenance", "unknown"))

    def content_hash(self) -> str:
        """SHA-256 of the axes, the values and the metadata (without its ``content_hash``)."""
        h = hashlib.sha256()
        h.update(f"{FORMAT}:{self.version}".encode())
        for name in (*AXES, *self.arrays()):
            arr = np.ascontiguousarray(self.array(name) if name not in AXES else getattr(self, name), dtype="<f8")
            h.update(name.encode())
            h.update(str(arr.shape).encode())
            h.update(arr.tobytes())
        meta = {k: v for k, v in self.metadata.items() if k != "content_hash"}
        h.update(json.dumps(meta, sort_keys=True, separators=(",", ":")).encode())
        return h.hexdigest()

    @functools.cached_property
    def native(self) -> "NativeTable":
        """The table in the native core, where every lookup is made (made on first use; not pickled)."""
        return NativeTable(self)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("native", None)
        return state

    def interpolate(self, pressure, velocity, beta, policy: str = "clamp") -> tuple[np.ndarray, np.ndarray]:
        """mu at the query points (broadcast together), interpolated as the format version says (module docstring).

        Parameters
        ----------
        pressure, velocity, beta : array_like
            Query points [Pa], [m/s] (the magnitude is used), [-].
        policy : {"clamp", "error"}
            What to do with queries outside the axes.

        Returns
        -------
        mu : ndarray
            Interpolated friction coefficients.
        clamped : ndarray of bool
            Which queries were outside the axes (and clamped) or read a node the campaign did not simulate.

        Raises
        ------
        TableDomainError
            Under ``policy="error"``, naming the quantity, the value and the table's range.
        """
        return self.interpolate_array(self.mu, pressure, velocity, beta, policy)

    def interpolate_array(self, values: np.ndarray, pressure, velocity, beta, policy: str = "clamp"):
        """One array with the table's shape (``mu``, an area, a standard error ...) interpolated as
        :meth:`interpolate`."""
        if policy not in ("clamp", "error"):
            raise ParameterError(f"table policy = {policy!r} is not allowed; choose clamp or error")
        values = np.ascontiguousarray(values, dtype=np.float64)
        if values.shape != self.mu.shape:
            raise ParameterError(f"an array of shape {values.shape} cannot be interpolated in a table of shape "
                                 f"{self.mu.shape}")
        p, v, b = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (pressure, velocity, beta)))
        out, clamped = self.native.lookup(values, p, v, b, policy == "error")
        return (out if out.ndim else float(out)), clamped

    def read_nodes(self, pressure: float, velocity: float, beta: float) -> tuple[list, bool]:
        """The nodes a lookup at one point reads (``[((i, j, k), weight), ...]``, the weights above
        :data:`READ_WEIGHT`) and whether the point is outside an axis (located then at the nearest edge)."""
        return self.native.read_nodes(pressure, velocity, beta)

    def reads_unsimulated(self, pressure: float, velocity: float, beta: float) -> bool:
        """Whether a lookup at one point reads a node the campaign did not simulate (a version 3 or 4 table)."""
        if self.version < 3:
            return False
        sim = self.extras["simulated"]
        return any(sim[node] == 0.0 for node, _ in self.read_nodes(pressure, velocity, beta)[0])


class NativeTable:
    """A friction table in the native core (``tc_table``), made from a :class:`FrictionTable`'s arrays: every lookup
    of the strip-draw model, its FMU and of :meth:`FrictionTable.interpolate` is made here."""

    def __init__(self, table: FrictionTable):
        from tribocosim.components.native.toolchain.library import VP, core, ptr

        c = self._core = core()
        self._ptr = ptr
        self.handle = VP()
        self.shape = table.mu.shape
        self._arrays = [np.ascontiguousarray(getattr(table, k), dtype=float) for k in ("pressure", "velocity", "beta",
                                                                                    "mu")]
        p, v, b, mu = self._arrays
        c.call(c.lib.tc_table_from_arrays, p.size, v.size, b.size, ptr(p), ptr(v), ptr(b), ptr(mu),
               table.beta_threshold, ctypes.byref(self.handle))
        if table.version >= 2:
            areas = [np.ascontiguousarray(getattr(table, k), dtype=float) for k in AREAS]
            self._arrays += areas
            c.call(c.lib.tc_table_set_areas, self.handle, *(ptr(a) for a in areas))
        if table.version >= 3:
            extras = [np.ascontiguousarray(table.array(k), dtype=float)
                      for k in ("simulated", "particle_area_clusters")]
            self._arrays += extras
            c.call(c.lib.tc_table_set_extras, self.handle, *(ptr(a) for a in extras))
        if table.version >= 4:
            c.call(c.lib.tc_table_set_cubic, self.handle)

    def lookup(self, values: np.ndarray, p: np.ndarray, v: np.ndarray, b: np.ndarray, refuse: bool):
        """``values`` (C-contiguous, the table's shape) at the points (same shape), one native call per pressure;
        ``(out, clamped)``. TableDomainError outside the axes when ``refuse``."""
        from tribocosim.components.native.toolchain.library import UBYTE_P

        c, ptr = self._core, self._ptr
        out = np.empty(p.shape)
        clamped = np.zeros(p.shape, dtype=bool)
        for value in np.unique(p):
            at = p == value
            vq, bq = np.ascontiguousarray(v[at]), np.ascontiguousarray(b[at])
            o, flags = np.empty(vq.size), np.zeros(vq.size, dtype=np.uint8)
            c.call(c.lib.tc_table_lookup, self.handle, ptr(values), float(value), vq.size, ptr(vq), ptr(bq),
                   int(refuse), ptr(o), ptr(flags, UBYTE_P), discard=TableDomainError)
            out[at], clamped[at] = o, flags.astype(bool)
        return out, clamped

    def read_nodes(self, pressure: float, velocity: float, beta: float) -> tuple[list, bool]:
        """:meth:`FrictionTable.read_nodes` (tc_table_read_nodes)."""
        nodes, weights, out = (ctypes.c_size_t * 8)(), (ctypes.c_double * 8)(), ctypes.c_int(0)
        n = self._core.lib.tc_table_read_nodes(self.handle, float(pressure), float(velocity), float(beta), nodes,
                                               weights, ctypes.byref(out))
        return [(tuple(int(x) for x in np.unravel_index(nodes[k], self.shape)), float(weights[k])) for k in range(n)], \
            bool(out.value)

    def __del__(self):
        if getattr(self, "handle", None):
            self._core.lib.tc_table_free(self.handle)
            self.handle = None


def mu_of_areas(mu0: float, particle_area, contact_area) -> np.ndarray:
    """The mu column of a version 2 or 3 table from its areas: mu = mu0 max(0, 1 - A_p / A_c) (Eq. 7 with Eq. 6),
    mu0 where A_c = 0."""
    ap, ac = np.asarray(particle_area, float), np.asarray(contact_area, float)
    return np.where(ac > 0, mu0 * np.maximum(0.0, 1.0 - ap / np.where(ac > 0, ac, 1.0)), mu0)


def write_table(path: str | os.PathLike, table: FrictionTable) -> str:
    """Write ``table`` to ``path`` (``.npz``) atomically and return its content hash."""
    meta = dict(table.metadata)
    meta.update(format=FORMAT, format_version=table.version,
                units={k: u for k, u in UNITS.items() if k in (*AXES, *table.arrays())})
    meta.pop("content_hash", None)
    stamped = dataclasses.replace(table, metadata=meta)
    digest = stamped.content_hash()
    meta["content_hash"] = digest
    from tribocosim.atomic import replaced

    with replaced(path, ".npz") as tmp:
        np.savez(
            tmp,
            **{name: getattr(stamped, name) for name in AXES},
            **{name: stamped.array(name) for name in stamped.arrays()},
            metadata=np.array(json.dumps(meta, sort_keys=True)),
        )
    return digest


def read_table(path: str | os.PathLike) -> FrictionTable:
    """Read and verify a friction table written by :func:`write_table`.

    Raises
    ------
    TableError
        If the file is missing or malformed, its format version is not supported, or its
        content hash does not match; the message names the path.
    """
    path = Path(path)
    if not path.is_file():
        raise TableError(f"friction table file not found: {path}")
    _check_is_archive(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(np.array(data["metadata"])))
            if not isinstance(meta, dict):
                raise ValueError("metadata is not a JSON object")
            version = meta.get("format_version")
            names = (*AXES, "mu", *(AREAS if version in (2, 3, 4) else ()), *(EXTRAS if version in (3, 4) else ()),
                     *(EXTRAS_4 if version == 4 else ()))
            arrays = {k: np.array(data[k]) for k in names if version in VERSIONS}
    except Exception as exc:  # noqa: BLE001 - any parse failure is a malformed file
        raise TableError(f"friction table {path} is malformed: {exc}") from exc
    if meta.get("format") != FORMAT or meta.get("format_version") not in VERSIONS:
        raise TableError(
            f"friction table {path} has format {meta.get('format')!r} version "
            f"{meta.get('format_version')!r}; this version reads {FORMAT!r} versions "
            f"{' and '.join(map(str, VERSIONS))}"
        )
    try:
        table = FrictionTable(arrays["pressure"], arrays["velocity"], arrays["beta"], arrays["mu"], meta,
                              **{a: arrays[a] for a in AREAS if a in arrays},
                              extras={a: arrays[a] for a in (*EXTRAS, *EXTRAS_4) if a in arrays})
    except (ParameterError, ValueError, TypeError) as exc:  # also members that are not float arrays
        raise TableError(f"friction table {path} is malformed: {exc}") from exc
    if table.content_hash() != meta.get("content_hash"):
        raise TableError(f"friction table {path} fails its content hash check (modified or corrupt)")
    return table


def _check_is_archive(path: Path) -> None:
    """TableError unless the file starts as a zip archive (an ``.npz``): a text file, an ``.npy`` array or another
    format is named for what it is, not by numpy's reading of it."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(8)
    except OSError as exc:
        raise TableError(f"friction table {path} cannot be read: {exc.strerror or exc}") from None
    if head.startswith(b"PK\x03\x04") or head.startswith(b"PK\x05\x06"):
        return
    if head.startswith(b"\x93NUMPY"):
        what = "a single numpy array (.npy)"
    elif not head:
        what = "empty"
    elif all(32 <= b < 127 or b in (9, 10, 13) for b in head):
        what = "a text file"
    else:
        what = "not a zip archive"
    raise TableError(f"friction table {path} is not a friction table: {what}; allowed: an .npz archive written by "
                     "tribocosim's write_table (tribocosim surrogate build or table, or "
                     "python -m tribocosim.components.stripdraw.make_table)")


#: the suffix of a table's resource form (the native reader takes ``X.npz`` to mean ``X.tca``)
RESOURCE_SUFFIX = ".tca"


def resource_entries(table: FrictionTable) -> dict:
    """The entries of the table's resource form: axes, value arrays, ``format_version``, ``beta_threshold``,
    ``content_hash``, ``provenance`` (what the native model reads; further entries may be added without a change to
    its reader)."""
    entries = {name: getattr(table, name) for name in AXES}
    entries.update({name: table.array(name) for name in table.arrays()})
    entries["format_version"] = float(table.version)
    entries["beta_threshold"] = table.beta_threshold
    entries["content_hash"] = str(table.metadata.get("content_hash", ""))
    entries["provenance"] = table.provenance
    return entries


def write_table_resource(table_path: str | os.PathLike, out: str | os.PathLike | None = None) -> Path:
    """Read and verify the table file ``table_path`` and write its resource form to ``out`` (default: beside it,
    with the suffix ``.tca``), with the SHA-256 of the file's bytes as ``source_sha256``; returns the path written."""
    from tribocosim.components.native.resource_io.array_file import write_arrays

    table_path = Path(table_path)
    target = Path(out) if out is not None else table_path.with_suffix(RESOURCE_SUFFIX)
    raw = table_path.read_bytes() if table_path.is_file() else None
    entries = resource_entries(read_table(table_path))
    entries["source_sha256"] = hashlib.sha256(raw).hexdigest()
    return write_arrays(target, entries)
