"""The output folder of ``tribocosim run``: checked before the run, and held by one run at a time.

A run writes its files at the end (:func:`tribocosim.cosim.api.run`); a folder it cannot write would lose the whole
run, and two runs writing into one folder would overwrite each other's files without a word. So before the run
:class:`OutputFolder`

- makes the folder (a file in its place, a read-only parent or a folder such as ``/proc`` is an error naming the
  folder and the reason);
- takes the folder's lock, a file ``.tribocosim-run.lock`` created exclusively, holding the process id: creating it
  proves the folder writable, and while it exists another run into the folder is refused, naming the process
  (a lock whose process has ended, after a crash or a kill, is taken over);
- checks each file the run will write: not a folder, writable when it exists;

and removes the lock when the run ends, however it ends (an exception, Ctrl-C, SIGTERM through the console
script's handler).
"""

from __future__ import annotations

import os
from pathlib import Path

from tribocosim.errors import TribocosimError

LOCK_NAME = ".tribocosim-run.lock"


class OutputError(TribocosimError):
    """The results of a run cannot be written where they are asked for; the message says where and why."""


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (on this machine)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # it exists, as another user's
        return True
    except OSError:
        return False
    return True


class OutputFolder:
    """``with OutputFolder(folder, files):`` the folder checked and locked for the run (see the module docstring).

    Parameters
    ----------
    folder : Path
        Where the run writes.
    files : iterable of Path
        The files it will write (inside ``folder``).
    """

    def __init__(self, folder: Path, files) -> None:
        self.folder = Path(folder)
        self.files = [Path(f) for f in files]
        self.lock = self.folder / LOCK_NAME
        self._held = False

    def __enter__(self) -> "OutputFolder":
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except FileExistsError:
            raise OutputError(f"cannot write the results into {self.folder}: a file of that name is in the way") from None
        except OSError as exc:
            raise OutputError(f"cannot make the output folder {self.folder}: {exc.strerror or exc}") from None
        if not self.folder.is_dir():
            raise OutputError(f"cannot write the results into {self.folder}: it is not a folder")
        self._take_lock()
        try:
            for f in self.files:
                self._check_file(f)
        except OutputError:
            self.release()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        """Remove the lock (once)."""
        if self._held:
            self._held = False
            self.lock.unlink(missing_ok=True)

    def _take_lock(self) -> None:
        for _ in range(2):  # a second try after taking over a lock whose process has ended
            try:
                fd = os.open(self.lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pid = self._holder()
                if pid is not None and _alive(pid) and pid != os.getpid():
                    raise OutputError(f"another run (process {pid}) is writing into {self.folder}; two runs into one "
                                      "folder would overwrite each other's results: give this one another --out, or "
                                      f"wait for it (its lock: {self.lock})") from None
                self.lock.unlink(missing_ok=True)  # its process has ended: a crash or a kill left it
                continue
            except OSError as exc:
                raise OutputError(f"cannot write into the output folder {self.folder}: "
                                  f"{exc.strerror or exc}") from None
            with os.fdopen(fd, "w") as f:
                f.write(f"{os.getpid()}\n")
            self._held = True
            return
        raise OutputError(f"cannot take the lock {self.lock} of the output folder (another run keeps taking it)")

    def _holder(self) -> int | None:
        try:
            return int(self.lock.read_text().split()[0])
        except (OSError, ValueError, IndexError):
            return None

    def _check_file(self, path: Path) -> None:
        if path.is_dir():
            raise OutputError(f"cannot write the result file {path}: a folder of that name is in the way")
        if not path.parent.is_dir():
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise OutputError(f"cannot make the folder of the result file {path}: {exc.strerror or exc}") from None
        if path.exists() and not os.access(path, os.W_OK):
            raise OutputError(f"cannot write the result file {path}: it is not writable")


def run_files(plan, folder: Path, plot: bool) -> list[Path]:
    """The files a run of ``plan`` writes into ``folder`` (as :func:`tribocosim.cosim.api.run` names them): the
    ``[output]`` CSV and its JSON (or ``<scene>.run.json``), and the plot's PNG."""
    folder = Path(folder)
    if plan.scene.output.file:
        csv = folder / plan.scene.output.file
        return [csv, csv.with_suffix(".json"), *([csv.with_suffix(".png")] if plot else [])]
    return [folder / f"{plan.scene.path.stem}.run.json"]
