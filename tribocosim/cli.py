"""The ``tribocosim`` console script: a thin dispatcher over subcommands that live with their package.

Subcommand modules are imported lazily, so that for example ``tribocosim run`` never imports
numba, pyfftw or the mesoscale code. Each module named below provides ``main(argv) -> int``.
"""

from __future__ import annotations

import atexit
import importlib
import os
import sys

#: subcommand -> (module providing ``main(argv)``, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("tribocosim.cosim.apps.demo", "run the default strip-draw case and print mu_bar"),
    "run": ("tribocosim.cosim.apps.run_cli", "run a co-simulation scene (TOML) or SSP package (.ssp)"),
    "ssp": ("tribocosim.cosim.apps.ssp_cli", "SSP 1.0 packages: export a scene (ssp export SCENE -o RIG.ssp)"),
    "report": ("tribocosim.cosim.apps.report_cli", "error-vs-run-time, stability and paper-figure reports"),
    "calibrate": ("tribocosim.cosim.apps.calibrate", "fit the particle-borne area and the debris balance to measured "
                  "mu_bar and debris"),
    "export": ("tribocosim.cosim.apps.export_cli", "the friction law for a forming simulation: user friction "
                                                    "routines, LS-DYNA, Abaqus, a neutral table"),
    "fmu": ("tribocosim.components.fmus.fmu_cli", "build the project's FMUs"),
    "meso": ("tribocosim.surrogate.meso_cli", "mesoscale tools: surfaces, contact, sliding"),
    "surrogate": ("tribocosim.surrogate.surrogate_cli", "campaigns and the friction table"),
}


def _usage() -> str:
    lines = ["usage: tribocosim COMMAND [ARGS...]", "", "commands:"]
    lines += [f"  {name:<10} {help_}" for name, (_, help_) in COMMANDS.items()]
    lines += ["", "Run 'tribocosim COMMAND --help' for the options of a command."]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tribocosim`` console script."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0
    name, rest = args[0], args[1:]
    if name not in COMMANDS:
        print(f"tribocosim: unknown command {name!r}; known: {', '.join(COMMANDS)}", file=sys.stderr)
        return 2
    module_name = COMMANDS[name][0]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and module_name.startswith(exc.name):
            print(f"tribocosim: command {name!r} is not available in this version", file=sys.stderr)
            return 2
        raise
    try:
        return int(module.main(rest) or 0)
    except KeyboardInterrupt:  # a command that says nothing else: every file is written whole or not at all
        print(f"tribocosim {name}: interrupted by SIGINT; no file is left half-written", file=sys.stderr)
        return 130


def _exit_on_termination() -> None:
    """SIGTERM (and SIGHUP) end the process as an exception does: ``finally`` blocks and ``atexit`` handlers run, so
    the folders SSP packages were extracted to are removed and a run's lock on its output folder is released (by
    default Python dies at once and leaves them). The exit status is 128 + the signal's number, as a shell shows
    it."""
    import signal

    def stop(signum, frame):
        raise SystemExit(128 + signum)

    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), stop)


def console() -> None:
    """The console script: :func:`main`, then exit.

    The process ends without the interpreter's own teardown (``os._exit``) once what Python's exit does first, and
    what this process relies on, has happened: the ``atexit`` handlers have run, which remove the folders SSP packages
    were extracted to (:mod:`tribocosim.cosim.ssp.reader`) and the temporary folders of ``weakref.finalize``
    (``tempfile.TemporaryDirectory``), shut process pools down and flush the log; then every output is flushed. What
    is left out frees every object of every module one by one (28 million instructions after ``tribocosim run demo``,
    callgrind; the operating system takes the memory back at once). It is not left out while another thread runs
    (Python's exit waits for it), unless a pythonfmu FMU ran in this process (the reports' oscillator FMUs, a user's
    component in Python): pythonfmu 0.7's library releases the dictionary of the component's module once at every
    ``fmi2Instantiate`` without owning it (``findClass``: ``Py_DECREF`` of the borrowed ``PyModule_GetDict``), so its
    count is short by one per instance, and the teardown is what frees that module's objects. (The library's interpreter
    state, which it releases twice in ``exit``, is released once at the interpreter's exit:
    :mod:`tribocosim.cosim.engine.libraries`.)"""
    _exit_on_termination()
    code = main()
    threading = sys.modules.get("threading")
    if "pythonfmu" in sys.modules or threading is None or threading.active_count() == 1:
        atexit._run_exitfuncs()  # the handlers Py_FinalizeEx would run first, in the same (reverse) order
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):  # a closed pipe (| head) or stream: nothing more can be said there
                pass
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    console()
