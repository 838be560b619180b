"""The two-mass-oscillator FMUs of the co-simulation tests, built once and cached, and their scenes.

The report builds ``tests/cosim/fmus/OscMassA.py`` and ``OscMassB.py`` (pythonfmu scripts) exactly as
``tests/cosim/conftest.py`` does: each in its own subprocess (pythonfmu caches the slave module by
name inside a process), with ``--handle-state``. The built FMUs go to
``<FMU cache>/report-oscillator/<digest>/``, keyed by the SHA-256 of the two scripts, and are moved
into place with one rename, so concurrent reports never see half-written files.

The scripts live in the source tree (``tests/``), not in an installed wheel: :func:`oscillator_fmus`
raises :class:`Unavailable` with the reason when they cannot be found or built, and the report turns
that into a "not available" line.
"""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

NAMES = ("OscMassA", "OscMassB")


class Unavailable(RuntimeError):
    """A report family cannot run here; the message says why."""


def scripts_dir() -> Path:
    """``tests/cosim/fmus`` of the source tree this package sits in."""
    return Path(__file__).resolve().parents[2] / "tests" / "cosim" / "fmus"


def oscillator_fmus(cache: Path | None = None) -> Path:
    """Folder holding ``OscMassA.fmu`` and ``OscMassB.fmu`` (built on first use)."""
    from tribocosim.cosim.scene.fmucache import cache_dir

    src = scripts_dir()
    scripts = [src / f"{n}.py" for n in NAMES]
    missing = [str(s) for s in scripts if not s.is_file()]
    if missing:
        raise Unavailable(f"the oscillator FMU scripts are not in this installation: {', '.join(missing)}")
    h = hashlib.sha256()
    for s in scripts:
        h.update(s.read_bytes())
    root = Path(cache) if cache is not None else cache_dir() / "report-oscillator"
    dest = root / h.hexdigest()[:16]
    if all((dest / f"{n}.fmu").is_file() for n in NAMES):
        return dest
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".build-", dir=root))
    try:
        jobs = [(subprocess.Popen([sys.executable, "-m", "pythonfmu", "build", "-f", str(s), "--dest", str(tmp),
                                   "--handle-state"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True), s)
                for s in scripts]
        for proc, s in jobs:
            out, _ = proc.communicate(timeout=600)
            if proc.returncode != 0:
                raise Unavailable(f"building {s.name} with pythonfmu failed:\n{out}")
        try:
            tmp.rename(dest)
        except OSError:  # built concurrently by another process
            if not all((dest / f"{n}.fmu").is_file() for n in NAMES):
                raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return dest


#: the force-displacement coupling of the two oscillator FMUs, as scene ``[[connections]]``
CONNECTIONS = """[[connections]]
from = "b.force"
to = "a.force"

[[connections]]
from = "a.x1"
to = "b.x1"

[[connections]]
from = "a.v1"
to = "b.v1"
"""


def oscillator_scene(folder: Path, fmus: Path, *, step: float, stop: float, algorithm: str = "jacobi",
                     extrapolation: int = 0, k2: float = 10.0, adaptive: dict | None = None,
                     name: str = "osc.toml") -> Path:
    """Write the two-mass oscillator scene (force-displacement coupling, as the tests use it).

    Parameters are those of :class:`tribocosim.cosim.studies.monolithic.TwoMassOscillator` (m = 1, k1 = 10, k3 = 20,
    c1 = 0.2, c2 = 0.5, c3 = 0.3, x2(0) = 0.5) with coupling stiffness ``k2``. ``adaptive``, if
    given, is the ``[master.adaptive]`` table (the power bond for the energy estimator is declared).
    """
    ad = ""
    if adaptive:
        ad = "[master.adaptive]\n" + "\n".join(f"{k} = {v!r}" if not isinstance(v, str) else f'{k} = "{v}"'
                                               for k, v in adaptive.items())
    text = f"""[experiment]
start = 0.0
stop = {float(stop)!r}
step = {float(step)!r}

[master]
algorithm = "{algorithm}"
extrapolation = {int(extrapolation)}
{ad}

[fmus.a]
path = "{(fmus / 'OscMassA.fmu').as_posix()}"
parameters = {{ m = 1.0, k = 10.0, c = 0.2, x0 = 0.0, v0 = 0.0 }}

[fmus.b]
path = "{(fmus / 'OscMassB.fmu').as_posix()}"
parameters = {{ m = 1.0, k3 = 20.0, c3 = 0.3, k2 = {float(k2)!r}, c2 = 0.5, x0 = 0.5, v0 = 0.0 }}

{CONNECTIONS}
[[power_bonds]]
effort = ["b.force", "a.force"]
flow = ["a.v1", "b.v1"]

[output]
variables = ["a.x1", "a.v1", "b.x2", "b.v2", "b.force"]
"""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path
