"""A drive that plays a velocity profile: a component written in Python, as a pythonfmu FMU of its own.

The grip velocity v(t) is the profile of a CSV file (columns ``time`` [s] and ``velocity`` [m/s], times
increasing) interpolated linearly, held at its first value before the first time and at its last after the
last; the grip position x(t) = int_0^t v is the exact integral of that piecewise-linear v. Outputs are the values
at the FMU's current time (after ``fmi2DoStep(t, h)``: at t + h). The file is ``profile_file``: a name in the
FMU's resources (the default, ``velocity_profile.csv``, is packed in by the build) or an absolute path.

Build (pythonfmu packs the script and the listed files into the FMU's resources)::

    pythonfmu build -f MeasuredDrive.py velocity_profile.csv --handle-state

and name the FMU in a scene with ``path = "MeasuredDrive.fmu"`` (measured_drive.toml beside this file). The FMU
needs Python with pythonfmu's runtime in the host, nothing of tribocosim.
"""

import bisect
import csv
import math
import os

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real, String
from pythonfmu.enums import Fmi2Initial


def read_profile(path):
    """(times, velocities) of a profile file; ValueError naming the file and the row for a bad one."""
    times, velocities = [], []
    with open(path, newline="", encoding="utf-8") as f:
        rows = csv.reader(f)
        header = [h.strip() for h in next(rows)]
        if header[:2] != ["time", "velocity"]:
            raise ValueError(f"{path}: the header must be time,velocity, got {','.join(header)}")
        for n, row in enumerate(rows, start=2):
            t, v = float(row[0]), float(row[1])
            if not (math.isfinite(t) and math.isfinite(v)) or (times and t <= times[-1]):
                raise ValueError(f"{path}, row {n}: time = {t!r} s, velocity = {v!r} m/s: need finite values and "
                                 "increasing times")
            times.append(t)
            velocities.append(v)
    if not times:
        raise ValueError(f"{path}: no rows")
    return times, velocities


class MeasuredDrive(Fmi2Slave):
    """The grip moved at a velocity profile read from a file."""

    description = "grip drive that plays a velocity profile (a CSV file of time and velocity)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.profile_file = "velocity_profile.csv"
        self.time = 0.0
        self.times, self.velocities = [0.0], [0.0]
        self.register_variable(String("profile_file", causality=Fmi2Causality.parameter,
                                      variability=Fmi2Variability.fixed))
        out = dict(causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                   initial=Fmi2Initial.calculated)
        self.register_variable(Real("grip_velocity", description="velocity of the grip [m/s]",
                                    getter=lambda: self.velocity(self.time), **out))
        self.register_variable(Real("grip_position", description="position of the grip from its start [m]",
                                    getter=lambda: self.position(self.time), **out))

    def exit_initialization_mode(self):
        path = self.profile_file
        if not os.path.isabs(path):
            path = os.path.join(self.resources, path)
        self.times, self.velocities = read_profile(path)

    def velocity(self, t):
        ts, vs = self.times, self.velocities
        k = bisect.bisect_right(ts, t)
        if k == 0:
            return vs[0]
        if k == len(ts):
            return vs[-1]
        w = (t - ts[k - 1]) / (ts[k] - ts[k - 1])
        return vs[k - 1] + w * (vs[k] - vs[k - 1])

    def position(self, t):
        """int_0^t v: trapezoids between the knots (exact for a piecewise-linear v)."""
        knots = [0.0] + [s for s in self.times if 0.0 < s < t] + [t]
        return sum(0.5 * (b - a) * (self.velocity(a) + self.velocity(b)) for a, b in zip(knots, knots[1:]))

    def do_step(self, current_time, step_size):
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return {"time": self.time}

    def _set_fmu_state(self, state):
        self.time = state["time"]
