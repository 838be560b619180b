"""The error types of tribocosim, shared by every package.

One small hierarchy so that callers can catch what they can handle:

- ``TribocosimError``: base of everything raised on purpose.
- ``ParameterError`` (also a ``ValueError``): a parameter or input outside its allowed range;
  the message names the quantity, its value and what is allowed.
- ``TableError``: a friction table file that is missing, malformed, or fails its hash check.
- ``TableDomainError`` (also a ``ValueError``): a friction-table lookup outside the table's axes
  under the ``error`` policy.
- ``ConvergenceError``: an iterative solver did not reach its tolerance.
- ``SceneError``: a co-simulation scene or sweep file with problems: all of them, each a
  :class:`Problem` (file, key, message), in ``.problems`` and in one message.
- ``CosimStepError``: a co-simulation step that failed (names FMU, variable and time).
- ``CaseRecordError``: a campaign case file that cannot be read or does not match its digest (names the file).
- ``Interrupted``: work stopped by a signal (SIGINT, SIGTERM; :mod:`tribocosim.interrupt`): ``CampaignInterrupted``
  (its finished cases are kept), ``RunInterrupted`` (a co-simulation run: its accepted steps are written),
  ``SweepInterrupted`` (a sweep of runs: its finished cases are kept).
- ``MemoryLimitError``: a command would need more memory than it may take; refused before it allocates.
- ``RangeWarning`` (a warning category, also a ``RuntimeWarning``): a model's input or output outside the range it
  is built for; the model still computes, the results from there on are outside what it describes.
"""

from __future__ import annotations

import math


class TribocosimError(Exception):
    """Base class of every error tribocosim raises on purpose."""


class ParameterError(TribocosimError, ValueError):
    """A parameter or an input is outside its allowed range.

    ``fields``: ``[(name, message), ...]`` when the error is about named fields of a parameter set (every bad field
    of it, each with its own message); empty for a rule across fields.
    """

    def __init__(self, message: str = "", fields=()) -> None:
        super().__init__(message)
        self.fields = list(fields)


class TableError(TribocosimError):
    """A friction table file is missing, malformed, or fails its integrity check."""


class TableDomainError(TribocosimError, ValueError):
    """A friction-table lookup fell outside the table's axes under the ``error`` policy."""


class ConvergenceError(TribocosimError):
    """An iterative solver did not converge to its tolerance.

    ``contraction``: the ratio of successive residuals the solver observed (its geometric mean), NaN
    if it does not know one; ``iterations``: how many it took before giving up (0 if not counted).
    The message says both in words.
    """

    def __init__(self, message: str = "", *, contraction: float = float("nan"), iterations: int = 0) -> None:
        super().__init__(message)
        self.contraction = float(contraction)
        self.iterations = int(iterations)


class Problem:
    """One problem of a scene or sweep file: the file, the dotted key, what is wrong."""

    __slots__ = ("file", "key", "message")

    def __init__(self, file: str, key: str, message: str) -> None:
        self.file, self.key, self.message = file, key, message

    def __str__(self) -> str:
        return f"{self.file}: {self.key}: {self.message}"

    def __repr__(self) -> str:
        return f"Problem({self.file!r}, {self.key!r}, {self.message!r})"

    def __eq__(self, other) -> bool:
        if other.__class__ is not Problem:
            return NotImplemented
        return (self.file, self.key, self.message) == (other.file, other.key, other.message)

    def __hash__(self) -> int:
        return hash((self.file, self.key, self.message))


class SceneError(TribocosimError):
    """A scene or sweep file has one or more problems.

    ``SceneError(problems, what)`` with a list of :class:`Problem` and what was read (``"scene
    PATH"``); the message is ``"N problem(s) in WHAT:"`` and one line per problem. A plain
    message string is also accepted (``problems`` is then empty).
    """

    def __init__(self, problems, what: str = "") -> None:
        if isinstance(problems, str):
            self.problems: list[Problem] = []
            super().__init__(problems)
            return
        self.problems = list(problems)
        n = len(self.problems)
        super().__init__(f"{n} problem{'s' if n != 1 else ''} in {what}:\n  " + "\n  ".join(map(str, self.problems)))


class CosimStepError(TribocosimError):
    """A co-simulation step failed."""


class RunFailed(CosimStepError):
    """A co-simulation run stopped at a step it could not recover; ``result`` holds (and, when the run
    writes files, has written) everything accepted up to that point."""

    def __init__(self, message: str, result) -> None:
        super().__init__(message)
        self.result = result


class CaseRecordError(TribocosimError):
    """A campaign case file cannot be read, or its contents do not match the digest recorded with it."""

    def __init__(self, message: str, path=None) -> None:
        super().__init__(message)
        self.path = path


class Interrupted(TribocosimError):
    """Work stopped on a signal (:mod:`tribocosim.interrupt`); ``signum`` is the signal's number."""

    def __init__(self, message: str, signum: int) -> None:
        super().__init__(message)
        self.signum = int(signum)


class CampaignInterrupted(Interrupted):
    """A campaign stopped on a signal. The cases finished before it are on disk; the slides in progress were
    discarded."""


class SweepInterrupted(Interrupted):
    """A sweep of scene runs stopped on a signal: ``finished`` of its ``total`` cases are written and kept (a rerun
    resumes); the cases in progress were discarded."""

    def __init__(self, message: str, signum: int, finished: int = 0, total: int = 0) -> None:
        super().__init__(message, signum)
        self.finished, self.total = int(finished), int(total)


class RunInterrupted(Interrupted):
    """A co-simulation run stopped on a signal at a communication point; ``result`` holds (and, when the run writes
    files, has written) every step accepted up to it."""

    def __init__(self, message: str, signum: int, result=None) -> None:
        super().__init__(message, signum)
        self.result = result


class MemoryLimitError(TribocosimError):
    """A command would need more memory than the limit (the memory available, or the user's ``--max-memory``);
    ``need`` and ``limit`` in bytes. Raised before the allocation."""

    def __init__(self, message: str, need: int = 0, limit: int = 0) -> None:
        super().__init__(message)
        self.need = int(need)
        self.limit = int(limit)


class RangeWarning(RuntimeWarning):
    """A model's input or output is outside the range it is built for (a component's declared port range)."""


def check_finite(name: str, value: float) -> float:
    """Return ``value`` as float, or raise ``ParameterError`` if it is NaN or infinite."""
    x = float(value)
    if not math.isfinite(x):
        raise ParameterError(f"{name} = {value!r} is not finite; a finite number is required")
    return x


def check_range(
    name: str,
    value: float,
    low: float | None = None,
    high: float | None = None,
    *,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
    unit: str = "",
) -> float:
    """Check that ``value`` is finite and inside ``[low, high]`` (bounds optional).

    Raises
    ------
    ParameterError
        With a message that names the quantity, its value and the allowed range.
    """
    x = check_finite(name, value)
    lo_ok = low is None or (x >= low if low_inclusive else x > low)
    hi_ok = high is None or (x <= high if high_inclusive else x < high)
    if lo_ok and hi_ok:
        return x
    lb = "-inf" if low is None else f"{low:g}"
    hb = "inf" if high is None else f"{high:g}"
    lbr = "[" if (low is not None and low_inclusive) else "("
    hbr = "]" if (high is not None and high_inclusive) else ")"
    u = f" {unit}" if unit else ""
    raise ParameterError(f"{name} = {value!r}{u} is out of range; allowed: {lbr}{lb}, {hb}{hbr}{u}")
