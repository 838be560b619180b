"""Plots (matplotlib, imported lazily): a run's recorded variables (``tribocosim run --plot``), the
demo's figures, sweep curves and beta(X, t) maps from a StripDraw ``field_output`` file."""

from __future__ import annotations

from pathlib import Path


def plot_result(result, path: Path) -> Path:
    """Write one stacked subplot per recorded variable against time to ``path`` (PNG).

    Parameters
    ----------
    result : cosim.api.Result
    path : Path
        The image file to write.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(result.columns)
    units = result.metadata.get("outputs", {}).get("units", {})
    n = max(1, len(names))
    fig, axes = plt.subplots(n, 1, figsize=(7.0, 1.8 * n + 0.6), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(result.time, result.columns[name], lw=1.0)
        ax.set_ylabel(labelled(name, units.get(name, "")), fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    m = result.metadata["master"]
    fig.suptitle(f"{Path(result.metadata['scene']).name}: {m['algorithm']}, extrapolation {m['extrapolation']}", fontsize=9)
    return _save(fig, path, dpi=120)


def labelled(name: str, unit: str) -> str:
    """``name [unit]``, or ``name`` for a quantity without a unit ("" or "1")."""
    return f"{name} [{unit}]" if unit not in ("", "1") else name


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path, dpi: int = 130, **options) -> Path:
    """Lay ``fig`` out (tight_layout, or the tight bounding box ``bbox_inches="tight"`` when given), write it to
    ``path`` (PNG) and close it; returns the path."""
    import matplotlib.pyplot as plt

    if "bbox_inches" not in options:
        fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=dpi, **options)
    plt.close(fig)
    return path


def read_field(path) -> dict:
    """The arrays of a StripDraw ``field_output`` file (time, X, beta, U, contact, window; its format's owner
    is :mod:`tribocosim.components.native.resource_io.field_file`)."""
    from tribocosim.components.native.resource_io.field_file import read_fields

    return read_fields(path)


def pad_edges_in_material(field: dict):
    """Material coordinates [m] of the pad's entry and exit edges at each recorded time.

    Node i is under the pad when a <= X_i + U_i <= a + L_T; the edge is where X + U(X) crosses
    a (entry) or a + L_T (exit), found by linear interpolation (X + U increases with X).
    """
    import numpy as np

    a, b = field["window"]
    x = field["X"]
    entry = np.array([np.interp(a, x + u, x) for u in field["U"]])
    exit_ = np.array([np.interp(b, x + u, x) for u in field["U"]])
    return entry, exit_


def draw_beta_map(ax, field: dict, *, vmax=None, colorbar=True, label=None):
    """beta over strip position (material coordinate X, mm) and time, like the paper's Fig. 17a.

    The dashed lines are the pad's edges in material coordinates: the strip material between them
    is under the pad; the 'V' opens between the first point that met the pad (vertical line) and
    the pad's entry edge moving through the strip at the draw speed (inclined line).
    """
    t, x, beta = field["time"], field["X"] * 1e3, field["beta"]
    entry, exit_ = pad_edges_in_material(field)
    lo = max(0.0, float(entry.min()) * 1e3 - 10.0)
    hi = min(float(x[-1]), float(exit_.max()) * 1e3 + 10.0)
    mesh = ax.pcolormesh(x, t, beta, shading="nearest", cmap="viridis", vmin=0.0,
                         vmax=vmax if vmax is not None else max(float(beta.max()), 1e-12), rasterized=True)
    ax.plot(entry * 1e3, t, "w--", lw=0.8)
    ax.plot(exit_ * 1e3, t, "w--", lw=0.8)
    ax.set_xlim(lo, hi)
    ax.set_xlabel("position on the strip X [mm]")
    ax.set_ylabel("time [s]")
    if label:
        ax.set_title(label, fontsize=9)
    if colorbar:
        ax.figure.colorbar(mesh, ax=ax, label="debris area fraction beta [-]")
    return mesh


def plot_demo(result, field_file, out_dir, mu_bar: float | None = None) -> list[Path]:
    """The demo's three figures: mu vs sliding distance, the beta map, pull and normal force vs time."""
    import numpy as np

    plt = _pyplot()
    out_dir = Path(out_dir)
    t = result.time
    fn = result["press.normal_force"]
    fp = result["strip.pull_force"]
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(fn > 0, fp / (2.0 * fn), np.nan)
    s = result["strip.sliding_distance"] * 1e3
    files = []

    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    ax.plot(s, mu, lw=1.4, label="pull_force / (2 normal_force)  (Eq. 1)")
    ax.plot(s, result["strip.mu_mean"], "--", lw=1.0, label="strip mu_mean = F_S / F_N  (Eq. 28)")
    if mu_bar is not None:
        sel = t >= t[-1] - 0.2 * (t[-1] - t[0])
        ax.plot(s[sel], np.full(sel.sum(), mu_bar), "k:", lw=1.5, label=f"mu_bar = {mu_bar:.4f} (last 20 %)")
    ax.set_xlabel("sliding distance [mm]")
    ax.set_ylabel("friction coefficient mu [-]")
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Friction coefficient over the draw", fontsize=10)
    files.append(_save(fig, out_dir / "mu_vs_sliding_distance.png"))

    field = read_field(field_file)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    draw_beta_map(ax, field)
    ax.set_title("Debris beta(X, t) on the strip (cf. paper Fig. 17a); dashed: pad edges", fontsize=10)
    files.append(_save(fig, out_dir / "beta_map.png"))

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 4.8), sharex=True)
    a1.plot(t, fp / 1e3, lw=1.2, label="pull force (strip, both faces)")
    a1.plot(t, fn / 1e3, lw=1.2, label="normal force (press, one pad)")
    a1.plot(t, result["press.force_reference"] / 1e3, "k:", lw=1.0, label="press set-point")
    a1.set_ylabel("force [kN]")
    a1.grid(True, alpha=0.3)
    a1.legend(fontsize=8)
    a2.plot(t, result["drive.grip_velocity"] * 1e3, lw=1.2, label="grip velocity (drive)")
    a2.plot(t, result["drive.velocity_reference"] * 1e3, "k:", lw=1.0, label="velocity set-point")
    a2.set_ylabel("velocity [mm/s]")
    a2.set_xlabel("time [s]")
    a2.grid(True, alpha=0.3)
    a2.legend(fontsize=8)
    a1.set_title("Press and drawing machine", fontsize=10)
    files.append(_save(fig, out_dir / "forces.png"))
    return files


def plot_sweep(result, path: Path) -> Path:
    """A sweep's summary ``[sweep.plot] y`` against ``x``, one curve per ``series`` value; hollow where ``flag`` says a
    run is not steady, crossed where it warned or read the friction table outside its axes (``result.counts``)."""
    plt = _pyplot()
    sw = result.sweep
    spec = sw.plot
    x = spec.get("x") or next(n for n in sw.variables)
    y = spec.get("y") or sw.summaries[0].name
    series = spec.get("series") or ("pass" if sw.passes > 1 else None)
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    groups: dict = {}
    for r in result.rows:
        groups.setdefault(r[series] if series else "", []).append(r)
    flag = spec.get("flag")
    flagged = False
    units = getattr(result, "units", {}) or {}
    unit_of = (lambda name: f" {units[name]}" if units.get(name, "") not in ("", "1") else "")
    for key, rows in groups.items():
        rows = sorted(rows, key=lambda r: r[x])
        label = (f"{series} = {key:g}{unit_of(series)}" if series and not isinstance(key, str)
                 else (f"{series} = {key}" if series else None))
        (line,) = ax.plot([r[x] for r in rows], [r[y] for r in rows], "o-", lw=1.2, ms=4, label=label)
        bad = [r for r in rows if flag and abs(r[flag]) > 0.05 * abs(r[y])]
        if bad:
            flagged = True
            ax.plot([r[x] for r in bad], [r[y] for r in bad], "o", ms=8, mfc="white", mec=line.get_color(), zorder=3)
    if flagged:
        ax.plot([], [], "o", ms=8, mfc="white", mec="k", label=f"not steady ({flag} > 5 % of {y})")
    counts = getattr(result, "counts", [])
    marked = [r for r in result.rows if any(r.get(c) for c in counts)]
    if marked:  # the runs that warned or read the friction table outside its axes
        ax.plot([r[x] for r in marked], [r[y] for r in marked], "x", ms=9, mew=1.6, color="crimson", zorder=4,
                label=f"warned or read outside the table ({len(marked)} runs)")
    ax.set_xlabel(spec.get("xlabel", labelled(x, units.get(x, ""))))
    ax.set_ylabel(spec.get("ylabel", labelled(y, units.get(y, ""))))
    ax.grid(True, alpha=0.3)
    if series or flagged or marked:
        ax.legend(fontsize=8)
    ax.set_title(spec.get("title", sw.title), fontsize=10)
    return _save(fig, path)


def plot_beta_maps(files, labels, path: Path, *, mu_bar=None, title: str = "") -> Path:
    """beta(X, t) maps side by side on one colour scale (the paper's Fig. 17a, 18a, 19a)."""
    plt = _pyplot()
    fields = [read_field(f) for f in files]
    vmax = max(float(f["beta"].max()) for f in fields) or 1e-12
    n = len(fields)
    fig, axes = plt.subplots(1, n, figsize=(3.2 * n + 1.2, 4.0), sharey=True, squeeze=False)
    mesh = None
    for i, (ax, f, lab) in enumerate(zip(axes[0], fields, labels)):
        extra = f"\nmu_bar = {mu_bar[i]:.4f}" if mu_bar and mu_bar[i] is not None else ""
        mesh = draw_beta_map(ax, f, vmax=vmax, colorbar=False, label=lab + extra)
        if i:
            ax.set_ylabel("")
    fig.colorbar(mesh, ax=list(axes[0]), label="beta [-]")
    if title:
        fig.suptitle(title, fontsize=10, y=1.04)
    return _save(fig, path, dpi=120, bbox_inches="tight")
