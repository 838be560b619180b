"""Plot of a run's recorded variables (``tribocosim run --plot``); matplotlib is imported lazily."""

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
    n = max(1, len(names))
    fig, axes = plt.subplots(n, 1, figsize=(7.0, 1.8 * n + 0.6), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(result.time, result.columns[name], lw=1.0)
        ax.set_ylabel(name, fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    m = result.metadata["master"]
    fig.suptitle(f"{Path(result.metadata['scene']).name}: {m['algorithm']}, extrapolation {m['extrapolation']}", fontsize=9)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
