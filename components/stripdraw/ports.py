"""The strip-draw component's inputs and outputs: units, start values and the ranges the model is built for.

Part of the component's declaration (:mod:`tribocosim.components.stripdraw.component`, which names them in its
``COMPONENT``), in a module of their own so that the binding (:mod:`tribocosim.components.stripdraw.model`) reads
the same ranges as the FMU: an input outside one in a step, or an output that leaves one after it, is a warning of
both (:class:`tribocosim.errors.RangeWarning` in Python, a logged Warning status in the FMU).
"""

from __future__ import annotations

from tribocosim.components.description import Port

#: Start values of the inputs: the paper's test at P_N = 10 MPa on the default 35 x 35 mm pad.
DEFAULT_NORMAL_FORCE = 12250.0  # N = 10 MPa x 0.035 m x 0.035 m
DEFAULT_GRIP_VELOCITY = 0.08

INPUTS = (
    Port("normal_force", "N", "normal force F_N on one pad (>= 0)", DEFAULT_NORMAL_FORCE, low=0.0,
         why="the pads press on the strip"),
    Port("grip_velocity", "m/s", "velocity of the grip pulling the strip", DEFAULT_GRIP_VELOCITY, low=0.0,
         why="the grip pulls the strip through the pad; a grip moving back pushes the strip out of it"),
)
#: the model's OUTPUT_NAMES, in its order
OUTPUTS = (
    Port("pull_force", "N", "pull force on the whole strip (both faces); mu = pull_force / (2 normal_force)"),
    Port("friction_force", "N", "friction force F_S on the modelled face (sum of nodal friction forces)"),
    Port("mu_mean", "1", "mean friction coefficient F_S / F_N (Eq. 28)"),
    Port("sliding_distance", "m", "contact-weighted mean displacement of the strip under the pad"),
    Port("beta_mean", "1", "contact-weighted mean debris area fraction under the pad"),
    Port("beta_max", "1", "largest debris area fraction on the strip"),
    Port("contact_pressure", "Pa", "nominal contact pressure P = F_N / (tool_length tool_width)", high="hardness",
         why="a nominal pressure above the strip's hardness flattens every asperity: no strip-draw contact",
         initial_inputs=("normal_force",)),
    Port("grip_position", "m", "displacement of the grip", high="draw_length",
         why="the bar is built for draw_length; beyond it the strip's tail runs into the pad and out of it"),
    Port("table_clamp_count", "1", "cumulative number of nodal table lookups outside the table (clamped)",
         integer=True, end_warning="friction-table lookups read values outside the table's simulated range "
         "(table_clamp_count): there the friction rests on values the mesoscale campaign did not simulate "
         "(docs/model.md section 4)"),
)
