"""A mesoscale campaign: every case of a sweep run through the BEM-DEM slide, resumable.

A *case* is one :class:`~tribocosim.surrogate.slide_config.SlideConfig` (one pressure, velocity, debris
level, flake placement seed and surface pair) run through :func:`tribocosim.surrogate.coupling.run_slide`.
Its id is the first 16 hex digits of the SHA-256 of the canonical JSON of the configuration, so
the same case has the same id in every run and on every machine; a measured surface file enters it by
the SHA-256 of its bytes, not by its path (:func:`tribocosim.surrogate.measured_surfaces.identity`).

Layout of the output folder ``OUT``:

- ``OUT/campaign.json``: the sweep and the list of its cases (ids and labels);
- ``OUT/cases/<id>.json``: one finished case: labels, configuration, ``summary()`` of the slide
  (<A_p>/A0 of Eq. 22, <A_c>/A0, ...), wall time, host, code version, a computation token and the
  digest of the record and its series (:mod:`tribocosim.surrogate.case_record`);
  ``OUT/cases/<id>.npz``: its per-step series (A_c/A0, A_p/A0, blocked flakes, BEM iterations);
- ``OUT/cases/<id>.error.json``: a failed case with its error and traceback;
- ``OUT/campaign.log``: one JSON line per event (start, done, failed, invalid, interrupted, end).

Each file is written to a temporary name and renamed (``os.replace``), the ``.json`` of a case
last: a case counts as finished when its ``.json`` and ``.npz`` pass their digest check
(:func:`tribocosim.surrogate.case_record.check_case`), so a campaign killed at any moment resumes by
rerunning only the cases without such a pair. A case whose files fail the check (edited, truncated,
garbage) is reported with the file and rerun; a table is never built from it (:func:`load_records`).
Failed cases are retried by a rerun unless ``retry_failed=False``. A run stopped by a signal
(:mod:`tribocosim.interrupt`) keeps every case finished before it and discards the slides in
progress. If the environment variable ``TRIBOCOSIM_CASE_LOG`` names a file, every computed case appends
its id there (an audit of computations across runs).
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import socket
import sys
import time
import traceback
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tribocosim.atomic import replaced, write_text
from tribocosim.errors import CampaignInterrupted, CaseRecordError, TribocosimError

from . import measured_surfaces
from .case_record import DIGEST_KEY, CheckedCase, case_digest, check_case
from .slide_config import SlideConfig
from .sweep import Sweep

CASE_FORMAT = 2
CASE_LOG_ENV = "TRIBOCOSIM_CASE_LOG"
SERIES = ("slide_distance", "contact_fraction", "particle_fraction", "particle_fraction_clusters",
          "n_blocked", "n_blocked_clusters", "bem_iterations", "tool_height", "particle_fraction_cluster_thresholds")


def code_version() -> str:
    """Installed tribocosim version, plus the git commit of the source tree when there is one."""
    try:
        from importlib.metadata import version

        ver = version("tribocosim")
    except Exception:  # noqa: BLE001 - not installed
        ver = "unknown"
    head = Path(__file__).resolve().parent.parent / ".git" / "HEAD"
    try:
        ref = head.read_text().strip()
        if ref.startswith("ref:"):
            ref = (head.parent / ref.split(" ", 1)[1]).read_text().strip()
        return f"{ver}+g{ref[:12]}"
    except OSError:
        return ver


@functools.lru_cache(maxsize=1)
def numerics() -> str:
    """What besides the project's code sets a slide's round-off, in one line: the processor as the JIT compiler sees it
    (numba compiles for the host's instruction set), the machine architecture, and the versions of numpy, numba and
    pyFFTW with its FFTW (FFTW's plans depend on both). A rerun is bit-identical to a recorded slide only with the same
    code and the same numerics (surrogate.verify)."""
    import platform

    parts = [platform.machine()]
    try:
        import llvmlite.binding as llvm

        parts.append(llvm.get_host_cpu_name())
    except Exception:  # noqa: BLE001 - the line says what it could not read
        parts.append("cpu ?")
    from importlib.metadata import PackageNotFoundError, version

    for dist in ("numpy", "numba", "pyFFTW"):
        try:
            parts.append(f"{dist} {version(dist)}")
        except PackageNotFoundError:
            parts.append(f"{dist} ?")
    return ", ".join(parts)


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """SHA-256 (12 hex digits) of the mesoscale sources (surrogate/*.py) and the table module.

    The git commit does not see uncommitted edits; this digest does. It is read once per process
    (a worker computes it at its first case, when it imports the slide code), recorded with every
    case and table, and not part of the case id (a rerun after an unrelated edit resumes).
    """
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for path in sorted(root.glob("*.py")) + [root.parent / "components" / "stripdraw" / "table.py"]:
        try:
            h.update(path.name.encode())
            h.update(path.read_bytes())
        except OSError:
            continue
    return h.hexdigest()[:12]


def case_id(config: SlideConfig) -> str:
    """Deterministic id of a case: SHA-256 of the canonical JSON of its configuration."""
    config_dict = measured_surfaces.identity(config.to_dict())
    blob = json.dumps({"case_format": CASE_FORMAT, "config": config_dict}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Case:
    """One slide of a campaign with the labels the fits group by."""

    config: SlideConfig
    labels: dict = field(default_factory=dict)

    @property
    def case_id(self) -> str:
        """Deterministic id (see :func:`case_id`)."""
        return case_id(self.config)

    def payload(self) -> dict:
        """What a worker needs: the id and the configuration as a plain dict."""
        return {"case_id": self.case_id, "config": self.config.to_dict()}


def make_case(sweep: Sweep, surface: int, pressure: float, velocity: float, count: int = 0,
              diameter: float | None = None, seed: int | None = None) -> Case:
    """The case of one member: a surface pair (index into ``sweep.surfaces``), a grid point and a
    debris level with a placement seed (count 0: particle-free, no seed). Labels: pressure, velocity,
    beta, n_flakes, flake_diameter, seed (None for particle-free cases) and surface."""
    kw = {**sweep.slide, **sweep.surfaces[surface], "pressure": pressure, "v0": velocity, "n_flakes": count,
          "flake_seed": 0 if seed is None else seed}
    if diameter is not None:
        kw["flake_diameter"] = diameter
    cfg = SlideConfig(**kw)
    labels = {"pressure": pressure, "velocity": velocity, "beta": cfg.beta, "n_flakes": count,
              "flake_diameter": cfg.flake_diameter if count else None, "seed": seed, "surface": surface}
    return Case(cfg, labels)


def expand_cases(sweep: Sweep) -> list[Case]:
    """Every case of ``sweep``: P x v x (flake levels x seeds [+ particle-free]) x surfaces, each level
    at the grid points it names (``FlakeLevel.at``) with its own seeds when it gives them.

    Particle-free cases (n_flakes = 0, beta = 0) do not depend on the placement seed: one per
    (P, v, surface).
    """
    cases: dict[str, Case] = {}
    for s_idx in range(len(sweep.surfaces)):
        for p in sweep.pressures:
            for v in sweep.velocities:
                levels = [(fl.count, fl.diameter, seed) for fl in sweep.flakes if fl.at(p, v)
                          for seed in (fl.seeds if fl.seeds is not None else sweep.seeds)]
                if sweep.particle_free:
                    levels.insert(0, (0, None, None))
                for count, d, seed in levels:
                    case = make_case(sweep, s_idx, p, v, count, d, seed)
                    cases.setdefault(case.case_id, case)
    return list(cases.values())


def relative_standard_error(values) -> float:
    """Standard error of the mean of ``values`` over their mean (inf with fewer than 2 values or a
    zero mean)."""
    x = np.asarray(values, dtype=float)
    if x.size < 2 or not np.mean(x) > 0:
        return math.inf
    return float(np.std(x, ddof=1) / math.sqrt(x.size) / np.mean(x))


def adaptive_cases(sweep: Sweep, records: list[dict]) -> list[Case]:
    """The next placements of the sweep's ``[adaptive]`` rule: at every node with flakes whose finished
    members' <A_p>/A0 has a relative standard error above the target (or a zero mean), the first extra
    seed the node has not used yet, on every surface pair. Empty when every node meets the target or
    has used every extra seed (or the sweep has no rule)."""
    if sweep.adaptive is None:
        return []
    nodes: dict = {}
    for r in records:
        lab = r["labels"]
        if lab["n_flakes"]:
            key = (lab["pressure"], lab["velocity"], lab["n_flakes"], lab["flake_diameter"])
            nodes.setdefault(key, []).append(r)
    out = []
    for (p, v, count, d), recs in sorted(nodes.items()):
        values = [r["summary"]["mean_particle_fraction"] for r in recs]
        if relative_standard_error(values) <= sweep.adaptive.target_relative_se:
            continue
        used = {r["labels"]["seed"] for r in recs}
        seed = next((x for x in sweep.adaptive.extra_seeds if x not in used), None)
        if seed is not None:
            out.extend(make_case(sweep, s, p, v, count, d, seed) for s in range(len(sweep.surfaces)))
    return out


def run_case(payload: dict) -> dict:
    """Run one case in a worker; returns a JSON-able dict (``status`` "done" or "failed").

    Never raises for a failing slide: the error type, message and traceback come back instead,
    so that one case cannot take a pool down.
    """
    t0 = time.perf_counter()
    base = {"case_id": payload["case_id"], "host": socket.gethostname(), "pid": os.getpid(),
            "token": uuid.uuid4().hex, "code_version": code_version(), "numerics": numerics()}
    try:
        from .coupling import run_slide

        base["source_digest"] = source_digest()  # of the code this process has just imported
        result = run_slide(SlideConfig(**payload["config"]))
        summary = result.summary()
        series = {k: np.asarray(getattr(result, k)).tolist() for k in SERIES if getattr(result, k, None) is not None}
    except Exception as exc:  # noqa: BLE001 - recorded with the case, the campaign goes on
        return {**base, "status": "failed", "wall_s": time.perf_counter() - t0,
                "error": {"type": type(exc).__name__, "message": str(exc),
                          "traceback": traceback.format_exc()}}
    out = {**base, "status": "done", "wall_s": time.perf_counter() - t0, "summary": summary,
           "series": series}
    log = os.environ.get(CASE_LOG_ENV)
    if log:
        with open(log, "a") as fh:
            fh.write(f"{payload['case_id']} {base['token']}\n")
    return out


def write_json(path: Path, data) -> None:
    """Write ``data`` as JSON to ``path`` atomically."""
    write_text(path, json.dumps(data, indent=1, sort_keys=True))


@dataclass(frozen=True)
class CaseState:
    """What is on disk for one case: ``status`` "finished" (``checked`` holds the record), "invalid" (its files
    fail :func:`~tribocosim.surrogate.case_record.check_case`: ``problem`` says which and why) or "missing"."""

    status: str
    checked: CheckedCase | None = None
    problem: str | None = None


class CampaignStore:
    """The files of a campaign folder (see the module docstring)."""

    def __init__(self, out: str | Path):
        self.out = Path(out)
        self.cases_dir = self.out / "cases"

    def case_path(self, cid: str) -> Path:
        return self.cases_dir / f"{cid}.json"

    def error_path(self, cid: str) -> Path:
        return self.cases_dir / f"{cid}.error.json"

    def state(self, cid: str) -> CaseState:
        """Whether case ``cid`` has a finished result on disk whose files pass their digest check."""
        try:
            return CaseState("finished", check_case(self.case_path(cid), cid))
        except FileNotFoundError:
            return CaseState("missing")
        except CaseRecordError as exc:
            return CaseState("invalid", problem=str(exc))

    def is_finished(self, cid: str) -> bool:
        """Whether a complete, intact result of case ``cid`` is on disk."""
        return self.state(cid).status == "finished"

    def read_case(self, cid: str) -> dict:
        """The record of a finished case (CaseRecordError if its files fail their check)."""
        return check_case(self.case_path(cid), cid).record

    def write_manifest(self, sweep: Sweep | None, cases: list[Case]) -> None:
        """Write ``OUT/campaign.json``; drop the temporary files of a writer that ended before its rename (a
        process stopped at once: :mod:`tribocosim.interrupt`)."""
        self.cases_dir.mkdir(parents=True, exist_ok=True)
        for tmp in [*self.cases_dir.glob(".*.tmp"), *self.out.glob(".*.tmp")]:
            pid = tmp.name.rsplit(".", 2)[-2]
            if pid.isdigit() and not _alive(int(pid)):
                tmp.unlink(missing_ok=True)
        write_json(self.out / "campaign.json", {
            "sweep": None if sweep is None else sweep.to_dict(),
            "cases": [{"case_id": c.case_id, "labels": c.labels} for c in cases],
        })

    def read_manifest(self) -> dict:
        path = self.out / "campaign.json"
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            raise TribocosimError(f"{path} cannot be read ({exc}); is {self.out} a campaign folder?") \
                from None

    def write_done(self, case: Case, outcome: dict) -> None:
        """The series (.npz), then the record (.json, the 'finished' marker) with the digest of both; drop an old
        error."""
        cid = case.case_id
        series = outcome.pop("series", None)
        arrays = None if series is None else {k: np.asarray(v) for k, v in series.items()}
        record = {**outcome, "labels": case.labels, "config": case.config.to_dict(), "finished_at": _now(),
                  "series_names": sorted(arrays or {})}
        record[DIGEST_KEY] = case_digest(record, arrays)
        npz = self.cases_dir / f"{cid}.npz"
        if arrays is not None:
            with replaced(npz) as tmp, open(tmp, "wb") as fh:
                np.savez_compressed(fh, **arrays)
        elif npz.exists():
            npz.unlink()
        write_json(self.case_path(cid), record)
        if self.error_path(cid).exists():
            self.error_path(cid).unlink()

    def write_failed(self, case: Case, outcome: dict) -> None:
        write_json(self.error_path(case.case_id), {**outcome, "labels": case.labels,
                                                  "config": case.config.to_dict(),
                                                  "failed_at": _now()})

    def log(self, event: str, cid: str | None = None, **extra) -> None:
        line = json.dumps({"t": _now(), "event": event, "case_id": cid, "pid": os.getpid(), **extra})
        with open(self.out / "campaign.log", "a") as fh:
            fh.write(line + "\n")
            fh.flush()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


class Progress:
    """A one-line progress bar with elapsed time and ETA on ``stream`` (stderr by default)."""

    def __init__(self, total: int, skipped: int = 0, stream=None, enabled: bool = True, width: int = 30):
        self.total, self.skipped, self.width = total, skipped, width
        self.stream = sys.stderr if stream is None else stream
        self.enabled = enabled
        self.done = self.failed = 0
        self.t0 = time.perf_counter()
        self._last = 0.0
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def update(self, ok: bool) -> None:
        if ok:
            self.done += 1
        else:
            self.failed += 1
        self.render()

    def line(self) -> str:
        finished = self.skipped + self.done + self.failed
        frac = finished / self.total if self.total else 1.0
        bar = "#" * int(round(frac * self.width))
        elapsed = time.perf_counter() - self.t0
        computed = self.done + self.failed
        remaining = self.total - finished
        eta = "--:--" if computed == 0 else _hms(elapsed / computed * remaining)
        return (f"[{bar:<{self.width}}] {finished}/{self.total} cases ({self.skipped} skipped, "
                f"{self.failed} failed) elapsed {_hms(elapsed)} ETA {eta}")

    def render(self, final: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not (final or self.tty or now - self._last >= 2.0):
            return
        self._last = now
        end = "\n" if (final or not self.tty) else ""
        self.stream.write(("\r" if self.tty else "") + self.line() + end)
        self.stream.flush()


def _hms(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


@dataclass
class CampaignReport:
    """What a campaign run did."""

    total: int
    skipped: list
    computed: list
    failed: list
    wall_s: float
    executor: dict

    def summary(self) -> str:
        return (f"{self.total} cases: {len(self.skipped)} already finished, {len(self.computed)} "
                f"computed, {len(self.failed)} failed in {self.wall_s:.1f} s on {self.executor}")


def run_campaign(cases: list[Case], out: str | Path, executor, *, sweep: Sweep | None = None,
                 retry_failed: bool = True, progress: bool = True, case_fn=run_case,
                 stream=None) -> CampaignReport:
    """Run every unfinished case of ``cases`` through ``executor``, writing each as it finishes.

    Parameters
    ----------
    cases : list of Case
        Typically :func:`expand_cases` of a sweep.
    out : path
        Campaign folder (created).
    executor
        A :mod:`tribocosim.surrogate.executors` executor.
    sweep : Sweep, optional
        Recorded in ``OUT/campaign.json``.
    retry_failed : bool
        Rerun cases that failed in an earlier run (default) or leave them failed.
    progress : bool
        Progress bar with ETA on stderr.
    case_fn : callable
        The worker function (importable; default :func:`run_case`).

    Raises
    ------
    CampaignInterrupted
        When a signal stops the executor (:mod:`tribocosim.interrupt`): the cases finished before it
        are written, the slides in progress discarded; ``exc.report`` is this run's report so far.
    """
    store = CampaignStore(out)
    store.write_manifest(sweep, cases)
    by_id = {c.case_id: c for c in cases}
    states = {cid: store.state(cid) for cid in by_id}
    skipped = [cid for cid, st in states.items() if st.status == "finished"]
    for cid, st in states.items():
        if st.status == "invalid":
            store.log("invalid", cid, problem=st.problem)
            _warn(stream, f"warning: {st.problem}; the case is computed again")
    legacy = sum(1 for cid in skipped if states[cid].checked.legacy)
    if legacy:
        _warn(stream, f"warning: {legacy} finished case record(s) in {store.cases_dir} carry no digest (written "
                      "before case digests): checked against their series only (tribocosim.surrogate.case_record)")
    done_before = set(skipped)
    todo = [cid for cid in by_id if cid not in done_before
            and (retry_failed or states[cid].status == "invalid" or not store.error_path(cid).exists())]
    left_failed = sorted(set(by_id) - done_before - set(todo))
    store.log("start", None, total=len(by_id), skipped=len(skipped), todo=len(todo),
              executor=executor.describe())
    bar = Progress(len(by_id), len(skipped) + len(left_failed), stream=stream, enabled=progress)
    bar.render()
    computed, failed = [], list(left_failed)
    t0 = time.perf_counter()

    def report() -> CampaignReport:
        return CampaignReport(len(by_id), skipped, computed, failed, time.perf_counter() - t0, executor.describe())

    try:
        for cid, outcome in executor.map_unordered(case_fn, [(cid, by_id[cid].payload()) for cid in todo]):
            case = by_id[cid]
            if isinstance(outcome, BaseException):
                outcome = {"case_id": cid, "status": "failed",
                           "error": {"type": type(outcome).__name__, "message": str(outcome),
                                     "traceback": "".join(traceback.format_exception(outcome))}}
            if outcome.get("status") == "done":
                store.write_done(case, outcome)
                store.log("done", cid, wall_s=outcome.get("wall_s"))
                computed.append(cid)
                bar.update(True)
            else:
                store.write_failed(case, outcome)
                err = outcome.get("error", {})
                store.log("failed", cid, error=f"{err.get('type')}: {err.get('message')}")
                failed.append(cid)
                bar.update(False)
    except (CampaignInterrupted, KeyboardInterrupt) as exc:
        bar.render(final=True)
        rep = report()
        store.log("interrupted", None, reason=str(exc) or type(exc).__name__, computed=len(computed),
                  failed=len(failed), not_finished=len(todo) - len(computed) - (len(failed) - len(left_failed)),
                  wall_s=rep.wall_s)
        exc.report = rep
        raise
    bar.render(final=True)
    rep = report()
    store.log("end", None, computed=len(computed), failed=len(failed), wall_s=rep.wall_s)
    return rep


def _warn(stream, message: str) -> None:
    out = sys.stderr if stream is None else stream
    out.write(message + "\n")
    out.flush()


def run_sweep(sweep: Sweep, out: str | Path, executor, **kwargs) -> CampaignReport:
    """Run every case of ``sweep`` (:func:`run_campaign`), then, while its ``[adaptive]`` rule asks for
    more (:func:`adaptive_cases` of the finished records), the added cases; returns the report of all
    rounds. Deterministic in the finished results, so an interrupted run resumes: every round skips
    the cases already on disk and the rule adds the same cases again."""
    cases = expand_cases(sweep)
    reports = []
    while True:
        reports.append(run_campaign(cases, out, executor, sweep=sweep, **kwargs))
        ids = {c.case_id for c in cases}
        done = load_records(out)[1]
        more = [c for c in adaptive_cases(sweep, done) if c.case_id not in ids]
        if not more:
            break
        cases = cases + more
    last = reports[-1]
    return CampaignReport(last.total, last.skipped[:len(reports[0].skipped)],
                          [c for r in reports for c in r.computed], last.failed,
                          sum(r.wall_s for r in reports), last.executor)


def load_records(out: str | Path) -> tuple[dict, list[dict], list[dict]]:
    """The manifest, the finished case records and the unfinished ones of a campaign folder.

    Only the cases listed in ``OUT/campaign.json`` count (old files of another sweep are ignored). A finished
    record passes its digest check (:func:`tribocosim.surrogate.case_record.check_case`) and has the labels the
    manifest gives its case. Every other case is in the third list with ``status``: "failed" (its
    ``.error.json``, whose path is ``file``), "invalid" (files that fail the check: ``file`` and
    ``error.message`` say which and why) or "missing" (never computed, or stopped before it finished).
    """
    store = CampaignStore(out)
    manifest = store.read_manifest()
    done, failed = [], []
    for entry in manifest["cases"]:
        cid, labels = entry["case_id"], entry["labels"]
        st = store.state(cid)
        if st.status == "finished":
            rec = st.checked.record
            if not st.checked.legacy and rec.get("labels") != labels:
                st = CaseState("invalid", problem=f"case record {store.case_path(cid)} has the labels "
                                                  f"{rec.get('labels')}, but {store.out / 'campaign.json'} gives "
                                                  f"its case {labels}")
            else:
                done.append({**rec, "labels": labels})
                continue
        if st.status == "invalid":
            failed.append({"case_id": cid, "labels": labels, "status": "invalid", "file": str(store.case_path(cid)),
                           "error": {"type": "CaseRecordError", "message": st.problem}})
        elif store.error_path(cid).exists():
            path = store.error_path(cid)
            try:
                err = json.loads(path.read_text())
            except (OSError, ValueError) as exc:
                err = {"case_id": cid, "labels": labels, "status": "failed",
                       "error": {"type": type(exc).__name__, "message": f"{path} cannot be read: {exc}"}}
            failed.append({**err, "status": "failed", "file": str(path)})
        else:
            failed.append({"case_id": cid, "labels": labels, "status": "missing"})
    return manifest, done, failed


def case_cpu_seconds(records: list[dict]) -> float:
    """Sum of the wall times of the cases (one core each): the cost of a campaign."""
    return float(sum(r.get("wall_s", 0.0) for r in records if math.isfinite(r.get("wall_s", 0.0))))
