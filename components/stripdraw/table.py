"""The friction table format: mu(P, v, beta) on a rectilinear grid, in one ``.npz`` file.

This module is the only owner of the format: the surrogate writes tables through
:func:`write_table`, the strip-draw model and its FMU read them through :func:`read_table`.

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
``metadata``               0-d str (JSON object)          see below
=========================  =============================  ===========================================

Version 2 carries the contact areas behind mu, so that the strip-draw model can compute
mu = mu0 (1 - A_p / A_c) with either contact-area convention (docs/model.md section 4); version 3 adds
where the values were simulated (the others come from the fit of A_p(beta) and are counted when read,
docs/model.md section 4), the standard errors of the tabulated areas, and the flake-borne area of the
paper's blocking rule alone (Fig. 8) beside that of every load-bearing flake; versions 1 (mu only) and 2
stay readable. ``metadata`` always holds ``format`` (``"tribocosim-friction-table"``),
``format_version`` (1, 2 or 3), ``units`` (array -> unit), ``provenance`` (``"closed_form"`` or
``"mesoscale"``), ``beta_threshold`` (the cap of beta, Eq. 24) and ``content_hash``: the SHA-256
of the axes and arrays (float64, little-endian, C order) and of the canonical JSON of the other
metadata. A file whose hash or format version does not match is refused.

The native code reads the table in its resource form (:func:`write_table_resource`): an array file
(:mod:`tribocosim.components.native.resource_io.array_file`) with the axes, mu, the areas (version 2), ``beta_threshold``,
``content_hash``, ``provenance`` and ``source_sha256`` (the SHA-256 of the bytes of the ``.npz`` it was written
from), written from a verified table (the FMU build bundles it as ``friction_table.tca``; a table file ``X.npz`` has
its resource at ``X.tca``). The native reader refuses ``X.tca`` when ``X.npz`` exists and its SHA-256 is not the
recorded one: a table replaced after its resource was written is never served from the old resource.

Interpolation is trilinear in (P, v, beta) and exact on the grid nodes. Queries outside the axes
follow a policy: ``"clamp"`` (evaluate at the nearest edge and count the clamped lookups, so the
caller can report them) or ``"error"`` (raise :class:`~tribocosim.errors.TableDomainError`). A query
within ``AXIS_END_TOLERANCE`` (1e-9, relative) of an axis end is on the end.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError, TableDomainError, TableError

FORMAT = "tribocosim-friction-table"
FORMAT_VERSION = 3  # written when the table carries the version 3 arrays; 1 and 2 are still read and written
VERSIONS = (1, 2, 3)
AXES = ("pressure", "velocity", "beta")
#: a query within this of an axis end (relative to the end) is on the end, not outside the table: the round-off of
#: the inputs (a press holding a set-point equal to the last pressure delivers it to within 1e-15 on either side);
#: the native lookup (tc_table_lookup.c) uses the same
AXIS_END_TOLERANCE = 1e-9
AREAS = ("contact_area", "particle_area", "contact_area_std", "particle_area_std")
#: the version 3 arrays (all of them, or none)
EXTRAS = ("simulated", "contact_area_se", "particle_area_se", "particle_area_clusters", "particle_area_clusters_se")
UNITS = {"pressure": "Pa", "velocity": "m/s", "beta": "1", "mu": "1", **{a: "1" for a in (*AREAS, *EXTRAS)}}


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
        Version 3 (with the version 2 areas): every array of :data:`EXTRAS` by name, same shape as ``mu``.
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
        if extras and (sorted(extras) != sorted(EXTRAS) or not given):
            raise ParameterError(f"table extras: {sorted(extras)} given; a version 3 table needs the version 2 "
                                 f"areas and all of {list(EXTRAS)}")
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
        bt = self.metadata.get("beta_threshold")
        if bt is None or not (0 < float(bt) <= 1):
            raise ParameterError(f"table metadata beta_threshold = {bt!r}; a value in (0, 1] is required")
        object.__setattr__(self, "metadata", dict(self.metadata))

    @property
    def version(self) -> int:
        """The format version: 3 with the version 3 arrays, 2 with the areas, else 1."""
        return 3 if self.extras else 2 if self.contact_area is not None else 1

    def arrays(self) -> tuple[str, ...]:
        """The names of the value arrays this table holds (``mu``, the areas in version 2, the extras in 3)."""
        return ("mu", *AREAS, *EXTRAS)[: {1: 1, 2: 1 + len(AREAS), 3: 1 + len(AREAS) + len(EXTRAS)}[self.version]]

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

    def interpolate(self, pressure, velocity, beta, policy: str = "clamp") -> tuple[np.ndarray, np.ndarray]:
        """Trilinear interpolation of mu at the query points (broadcast together).

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
            Which queries were outside the axes (and clamped).

        Raises
        ------
        TableDomainError
            Under ``policy="error"``, naming the quantity, the value and the table's range.
        """
        return self.interpolate_array(self.mu, pressure, velocity, beta, policy)

    def interpolate_array(self, values: np.ndarray, pressure, velocity, beta, policy: str = "clamp"):
        """Trilinear interpolation of one of the table's arrays (``mu`` or an area), as :meth:`interpolate`."""
        if policy not in ("clamp", "error"):
            raise ParameterError(f"table policy = {policy!r} is not allowed; choose clamp or error")
        p = np.asarray(pressure, float)
        v = np.abs(np.asarray(velocity, float))
        b = np.asarray(beta, float)
        if p.ndim == 0:
            # one pressure for all queries (the strip-draw case): interpolate in P once, then
            # bilinearly in (v, beta)
            ip, tp, outp = self._locate("pressure", p, policy)
            ip, tp = int(ip), float(tp)
            plane = values[ip] if self.pressure.size == 1 else (1.0 - tp) * values[ip] + tp * values[ip + 1]
            v, b = np.broadcast_arrays(v, b)
            iv, tv, outv = self._locate("velocity", v, policy)
            ib, tb, outb = self._locate("beta", b, policy)
            sv = min(1, self.velocity.size - 1)
            sb = min(1, self.beta.size - 1)
            out = ((1.0 - tv) * ((1.0 - tb) * plane[iv, ib] + tb * plane[iv, ib + sb])
                   + tv * ((1.0 - tb) * plane[iv + sv, ib] + tb * plane[iv + sv, ib + sb]))
            return out, outv | outb | bool(outp)
        p, v, b = np.broadcast_arrays(p, v, b)
        located = [self._locate(name, q, policy) for name, q in zip(AXES, (p, v, b))]
        (ip, tp, op), (iv, tv, ov), (ib, tb, ob) = located
        out = np.zeros(p.shape)
        sp, sv, sb = (min(1, getattr(self, n).size - 1) for n in AXES)
        for dp in (0, sp):
            wp = tp if dp else 1.0 - tp
            for dv in (0, sv):
                wv = tv if dv else 1.0 - tv
                for db in (0, sb):
                    wb = tb if db else 1.0 - tb
                    out += wp * wv * wb * values[ip + dp, iv + dv, ib + db]
        return out, op | ov | ob

    def _locate(self, name: str, q: np.ndarray, policy: str):
        """Cell index, local coordinate in [0, 1] and out-of-range mask of queries on one axis."""
        axis = getattr(self, name)
        out = (q < axis[0] - AXIS_END_TOLERANCE * abs(axis[0])) | (q > axis[-1] + AXIS_END_TOLERANCE * abs(axis[-1]))
        if policy == "error" and np.any(out):
            bad = float(np.asarray(q)[out].flat[0]) if np.ndim(q) else float(q)
            raise TableDomainError(
                f"friction table lookup {name} = {bad!r} {UNITS[name]} is outside the table's "
                f"range [{axis[0]:g}, {axis[-1]:g}] {UNITS[name]}"
            )
        qc = np.minimum(np.maximum(q, axis[0]), axis[-1])
        if axis.size == 1:
            return np.zeros(np.shape(q), dtype=np.intp), np.zeros(np.shape(q)), out
        i = np.minimum(np.searchsorted(axis, qc, side="right") - 1, axis.size - 2)
        t = (qc - axis[i]) / (axis[i + 1] - axis[i])
        return i, t, out


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
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(
        tmp,
        **{name: getattr(stamped, name) for name in AXES},
        **{name: stamped.array(name) for name in stamped.arrays()},
        metadata=np.array(json.dumps(meta, sort_keys=True)),
    )
    os.replace(tmp, path)
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
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(np.array(data["metadata"])))
            if not isinstance(meta, dict):
                raise ValueError("metadata is not a JSON object")
            version = meta.get("format_version")
            names = (*AXES, "mu", *(AREAS if version in (2, 3) else ()), *(EXTRAS if version == 3 else ()))
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
                              extras={a: arrays[a] for a in EXTRAS if a in arrays})
    except (ParameterError, ValueError, TypeError) as exc:  # also members that are not float arrays
        raise TableError(f"friction table {path} is malformed: {exc}") from exc
    if table.content_hash() != meta.get("content_hash"):
        raise TableError(f"friction table {path} fails its content hash check (modified or corrupt)")
    return table


#: the suffix of a table's resource form (the native reader takes ``X.npz`` to mean ``X.tca``)
RESOURCE_SUFFIX = ".tca"


def resource_entries(table: FrictionTable) -> dict:
    """The entries of the table's resource form: axes, value arrays, ``beta_threshold``, ``content_hash``,
    ``provenance`` (what the native model reads; further entries may be added without a change to its reader)."""
    entries = {name: getattr(table, name) for name in AXES}
    entries.update({name: table.array(name) for name in table.arrays()})
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
