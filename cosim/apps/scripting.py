"""``tribocosim.run``: a scene run from a Python script, its results in memory unless a folder is given.

:func:`tribocosim.cosim.api.run` writes the CSV and the JSON by default (into the scene's folder, or ``./<name>`` for a
packaged scene), as the command line does; a script that only reads the :class:`~tribocosim.cosim.api.Result` should
not find files in its working folder that it did not ask for. So here the files are written only into ``out_dir``,
when it is given.
"""

from __future__ import annotations

from pathlib import Path


def run(scene, out_dir: str | Path | None = None, *, overrides: dict | None = None, progress: bool = False):
    """Load, check and run a scene; return its :class:`~tribocosim.cosim.api.Result`.

    Parameters
    ----------
    scene : str, Path or Plan
        A scene file, the name of a packaged scene (``"demo"``), or a validated plan.
    out_dir : str or Path, optional
        Write the CSV and the metadata JSON there (the ``[output] file`` name); None: nothing is written.
    overrides : dict, optional
        Dotted scene keys to override, e.g. ``{"master.extrapolation": 1}`` (recorded in ``result.metadata``).
    progress : bool
        A progress bar on stderr for runs longer than two seconds.

    Examples
    --------
    >>> import tribocosim
    >>> result = tribocosim.run("stripdraw", overrides={"experiment.stop": 0.05})  # doctest: +SKIP
    >>> result["strip.pull_force"][-1]  # doctest: +SKIP
    """
    from tribocosim.cosim.api import run as run_scene

    return run_scene(scene, out_dir, overrides=overrides, progress=progress, write=out_dir is not None)
