"""What every report family returns, and small helpers (load average, timing).

A family is one function ``family(settings) -> Family`` that can run alone. It fills ``rows``
(one dict per setting: the CSV rows) or, when a piece it needs is missing, returns
``Family.unavailable(name, title, why)``, which the Markdown report prints as
"not available yet: <why>".
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path


def packaged_scene(name: str) -> Path:
    """A scene shipped with the package, ``models/scenes/<name>.toml``."""
    from tribocosim.paths import SCENES_DIR

    return SCENES_DIR / f"{name}.toml"


def instance_of(plan, component: str) -> str | None:
    """The first FMU instance of a validated plan whose scene names it ``component = "<component>"``, or None."""
    from tribocosim.cosim.scene.component_checks import component_of

    return next((n for n, s in plan.scene.fmus.items() if getattr(component_of(s), "name", None) == component), None)


def started_at_once(plan) -> dict:
    """The overrides that start a plan's drawing machine at t = 0 (``start_time`` = 0): the press's force ramp and
    the drive's velocity ramp then overlap, the hardest start for the coupling, which the accuracy and stability
    reports measure (the shipped demo holds the strip until the press has settled)."""
    drive = instance_of(plan, "drawingmachine")
    return {f"fmus.{drive}.parameters.start_time": 0.0} if drive else {}


@dataclass(frozen=True)
class Settings:
    """Settings shared by the families of one report run.

    Attributes
    ----------
    quick : bool
        Small sweeps (the CI mode: all families together in under 5 minutes on 2 cores).
    work : Path
        Scratch folder (scenes, FMU extractions).
    log : callable
        Progress messages (``print`` to stderr by default in the CLI).
    """

    quick: bool
    work: Path
    log: object = print


@dataclass
class Family:
    """The result of one report family.

    Attributes
    ----------
    name : str
        Short id (file names: ``<name>.csv``, ``<name>.png``).
    title : str
        Heading in the Markdown report.
    rows : list of dict
        One row per setting (the CSV).
    available : bool
        False: the family could not run; ``note`` says why.
    note : str
        Text under the heading: what is measured, the reference, the error and the cost.
    curve : str
        Column whose value names a curve of the plot (one curve per setting family).
    error, cost : str
        Columns plotted (log-log error against cost) and used by the summary table.
    label : str
        Column naming a setting in the summary table.
    wall_time : float
        Wall time of the whole family [s].
    load : str
        Load average before and after.
    """

    name: str
    title: str
    rows: list = field(default_factory=list)
    available: bool = True
    note: str = ""
    curve: str = ""
    error: str = "error"
    cost: str = "wall_time"
    label: str = "setting"
    wall_time: float = 0.0
    load: str = ""
    extra_md: str = ""
    errors: tuple = ()  # several error columns (one plot panel and one summary row each); default (error,)
    summary_curves: tuple = ()  # curves that also get their own summary rows (besides the family's cheapest)

    @property
    def error_columns(self) -> tuple:
        return self.errors or (self.error,)

    @classmethod
    def unavailable(cls, name: str, title: str, why: str) -> "Family":
        return cls(name, title, available=False, note=f"not available yet: {why}")


def load_average() -> str:
    """'1-min 5-min 15-min' load average (or 'n/a')."""
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover
        return "n/a"


def timed(family_fn):
    """Decorator: record wall time and load average (before / after) on the returned Family."""
    import functools

    @functools.wraps(family_fn)
    def wrapper(settings: Settings, *args, **kwargs) -> Family:
        before = load_average()
        t0 = time.perf_counter()
        fam = family_fn(settings, *args, **kwargs)
        fam.wall_time = time.perf_counter() - t0
        fam.load = f"load average before {before}, after {load_average()} (2 cores)"
        return fam

    return wrapper


def scratch(settings: Settings, name: str) -> Path:
    """A sub-folder of the scratch folder."""
    p = Path(settings.work) / name
    p.mkdir(parents=True, exist_ok=True)
    return p
