"""Writing the reports: CSV (raw data), PNG (plots) and the Markdown summary.

Every family writes ``<name>.csv`` (all columns of its rows) and, if it has rows, ``<name>.png``;
the report's Markdown file links them. The accuracy report opens with the summary table (the
cheapest setting of each family that reaches 1 %, 0.1 % and 0.01 %); the stability report with the
criterion and a matrix per family (cases x schemes, the verdict and the largest stable step).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from tribocosim.cosim.reports.common import Family
from tribocosim.cosim.reports.metrics import cheapest_reaching

TARGETS = (1e-2, 1e-3, 1e-4)


def fmt(x, digits: int = 3) -> str:
    """Compact number formatting for tables."""
    if x is None:
        return ""
    if isinstance(x, bool):
        return str(x)
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if math.isnan(x):
            return ""
        if math.isinf(x):
            return "inf"
        return f"{x:.{digits}g}"
    return str(x).replace("|", "/")


def write_csv(fam: Family, path: Path) -> Path | None:
    if not fam.rows:
        return None
    cols: list[str] = []
    for r in fam.rows:
        cols += [k for k in r if k not in cols]
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=cols)
        w.writeheader()
        for r in fam.rows:
            w.writerow({k: r.get(k, "") for k in cols})
    return path


def table(rows: list[dict], cols: list[str], headers: list[str] | None = None) -> str:
    headers = headers or cols
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        lines.append("| " + " | ".join(fmt(r.get(c)) for c in cols) + " |")
    return "\n".join(lines)


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_accuracy(fam: Family, path: Path) -> Path | None:
    """Log-log error against cost (wall time; and doStep calls when recorded), one curve per setting family."""
    rows = [r for r in fam.rows if isinstance(r.get(fam.cost), (int, float)) and r.get(fam.cost, 0) > 0]
    if not rows:
        return None
    plt = _plt()
    from matplotlib.ticker import NullFormatter

    costs = [fam.cost] + (["do_steps"] if any(r.get("do_steps") for r in rows) else [])
    errs = fam.error_columns
    fig, axes = plt.subplots(len(errs), len(costs), figsize=(6.0 * len(costs), 4.2 * len(errs)), squeeze=False)
    curves = list(dict.fromkeys(r.get(fam.curve or "curve", "") for r in rows))
    for i, e in enumerate(errs):
        for j, c in enumerate(costs):
            ax = axes[i][j]
            for k, name in enumerate(curves):
                pts = sorted((r[c], r[e]) for r in rows if r.get(fam.curve or "curve", "") == name
                             and isinstance(r.get(e), float) and math.isfinite(r[e]) and r[e] > 0 and r.get(c))
                if pts:
                    ax.loglog(*zip(*pts), marker="os^vDx<>p*h"[k % 11], linestyle="-" if k < 10 else "--", label=name)
            for t in TARGETS:
                ax.axhline(t, color="0.8", linewidth=0.8, zorder=0)
            ax.set_xlabel({"wall_time": "wall time [s]", "do_steps": "doStep calls",
                           "build_core_seconds": "build cost [core-s]"}.get(c, c))
            ax.set_ylabel(e.replace("_", " ") + " (relative)")
            ax.grid(True, which="both", alpha=0.3)
            ax.xaxis.set_minor_formatter(NullFormatter())
            if i == 0 and j == 0:
                ax.legend(fontsize=7, ncol=2)
    fig.suptitle(fam.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_stability(fam: Family, path: Path) -> Path | None:
    """Largest stable step per case (x) and scheme (one line each), log scale."""
    rows = [r for r in fam.rows if "stable_step" in r]
    if not rows:
        return None
    plt = _plt()
    cases = list(dict.fromkeys(r["case"] for r in rows))
    schemes = list(dict.fromkeys(r["scheme"] for r in rows))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(cases) + 3), 4.5))
    for k, s in enumerate(schemes):
        xs, ys, open_x, open_y = [], [], [], []
        for i, c in enumerate(cases):
            r = next((r for r in rows if r["case"] == c and r["scheme"] == s), None)
            if r is None or not r["stable_step"] > 0:
                continue
            (open_x if math.isinf(r["unstable_step"]) else xs).append(i)
            (open_y if math.isinf(r["unstable_step"]) else ys).append(r["stable_step"])
        line = ax.semilogy(xs, ys, marker="os^vDx<>p*h"[k % 11], label=s)[0]
        if open_x:
            ax.semilogy(open_x, open_y, marker="^", linestyle="none", color=line.get_color(), markerfacecolor="none")
    ax.set_xticks(range(len(cases)))
    ax.set_xticklabels(cases, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("largest stable step [s]\n(open marker: stable to the end of the range)", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(fam.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _head(fam: Family, files: list[Path]) -> list[str]:
    out = [f"## {fam.title}", ""]
    if not fam.available:
        return out + [f"**{fam.note}**", ""]
    out += [fam.note, "", f"Family wall time {fam.wall_time:.1f} s; {fam.load}.", ""]
    for f in files:
        if f.suffix == ".png":
            out += [f"![{fam.name}]({f.name})", ""]
    out += ["Raw data: " + ", ".join(f"[{f.name}]({f.name})" for f in files if f.suffix == ".csv"), ""]
    return out


def _cheapest_cell(row: dict | None, fam: Family) -> str:
    if row is None:
        return "not reached"
    cost = row[fam.cost]
    unit = {"wall_time": "s", "build_core_seconds": "core-s"}.get(fam.cost, "")
    extra = f", {row['do_steps']} doSteps" if row.get("do_steps") else ""
    return f"{row[fam.label]} ({fmt(cost)} {unit}{extra})"


def _cheapest_row(label: str, rows: list, fam: Family, error: str) -> str:
    """One summary line: the cheapest of ``rows`` reaching each target of ``error``."""
    best = cheapest_reaching(rows, TARGETS, error=error, cost=fam.cost, label=fam.label)
    return f"| {label} | {error} | " + " | ".join(_cheapest_cell(best[t], fam) for t in TARGETS) + " |"


def _curve_rows(fam: Family, curve: str) -> list:
    return [r for r in fam.rows if r.get("curve") == curve]


def accuracy_markdown(fams: list[Family], files: dict[str, list[Path]], header: str) -> str:
    out = [header, "", "## Summary: the cheapest setting reaching each error", "",
           "| family | error | <= 1 % | <= 0.1 % | <= 0.01 % |", "|---|---|---|---|---|"]
    for fam in fams:
        if not fam.available:
            out.append(f"| {fam.name} | | {fam.note} | | |")
            continue
        out += [_cheapest_row(fam.name, fam.rows, fam, e) for e in fam.error_columns]
        out += [_cheapest_row(f"{fam.name}: {c}", _curve_rows(fam, c), fam, e)
                for c in fam.summary_curves for e in fam.error_columns]
    out.append("")
    for fam in fams:
        out += _head(fam, files.get(fam.name, []))
        if fam.rows:
            curves = list(dict.fromkeys(r.get("curve", "") for r in fam.rows))
            if len(curves) > 1:
                out += ["Cheapest setting of each curve reaching each error:", "",
                        "| curve | error | <= 1 % | <= 0.1 % | <= 0.01 % |", "|---|---|---|---|---|"]
                out += [_cheapest_row(c, _curve_rows(fam, c), fam, e) for c in curves for e in fam.error_columns]
                out.append("")
            cols = [c for c in fam.rows[0] if c not in ("curve",)]
            out += ["All settings:", "", table(fam.rows, cols), ""]
    return "\n".join(out) + "\n"


def stability_markdown(fams: list[Family], files: dict[str, list[Path]], header: str, criterion_text: str) -> str:
    out = [header, "", "## Definition of stable", "", criterion_text, "",
           "A cell is `stable`, `unstable` (with the first failed test) or `error` (the run stopped with an error; "
           "the message). Below each verdict: the largest stable step found by bisection (`>= h`: stable up to the end "
           "of the range searched; `< h`: not stable even at the smallest step tried). Iterative coupling: `rho_obs`, the "
           "largest contraction factor observed in a step of the nominal run (the geometric mean ratio of successive "
           "coupling residuals; for the step whose iteration failed, its estimate up to the failure).", ""]
    for fam in fams:
        out += _head(fam, files.get(fam.name, []))
        if not fam.rows:
            continue
        cases = list(dict.fromkeys(r["case"] for r in fam.rows))
        schemes = list(dict.fromkeys(r["scheme"] for r in fam.rows))
        out += ["| case | " + " | ".join(schemes) + " |", "|---|" + "---|" * len(schemes)]
        notes = []
        for c in cases:
            cells = []
            for s in schemes:
                r = next((r for r in fam.rows if r["case"] == c and r["scheme"] == s), None)
                if r is None:
                    cells.append("")
                    continue
                cell = r["status"] if r["status"] == "stable" else f"**{r['status']}** [{len(notes) + 1}]"
                rho = r.get("observed_contraction")
                if isinstance(rho, float) and math.isfinite(rho):
                    cell += f", rho_obs = {fmt(rho, 2)}"
                if r["status"] != "stable":
                    notes.append(f"[{len(notes) + 1}] {c}, {s}: {r['reason']}")
                if "stable_step" in r:
                    if not r["stable_step"] > 0:
                        cell += f"<br>h_max < {fmt(r['unstable_step'])} s"
                    elif math.isinf(r["unstable_step"]):
                        cell += f"<br>h_max >= {fmt(r['stable_step'])} s"
                    else:
                        cell += f"<br>h_max = {fmt(r['stable_step'])} s"
                if isinstance(r.get("predicted_limit"), float) and math.isfinite(r["predicted_limit"]):
                    cell += f"<br>(predicted {fmt(r['predicted_limit'])} s)"
                cells.append(cell)
            out.append(f"| {c} | " + " | ".join(cells) + " |")
        out.append("")
        if notes:
            out += ["Why the cells are not stable:", ""] + [f"- {n}" for n in notes] + [""]
        lim = [r for r in fam.rows if r.get("limit_reason") and 0 < r.get("stable_step", 0) and not math.isinf(r["unstable_step"])]
        if lim:
            out += ["What fails just above the largest stable step:", ""]
            out += [f"- {r['case']}, {r['scheme']}: at {fmt(r['unstable_step'])} s: {r['limit_reason']}" for r in lim] + [""]
    return "\n".join(out) + "\n"
