import numpy as np
from tribocosim import DEFAULT_TABLE, StripDrawModel, StripDrawParameters, make_friction_law, read_table

p = StripDrawParameters()                                   # the paper's test: 35 x 35 mm pad, friction table law
model = StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))  # the shipped table
mu = []
for k in range(1750):                                       # 140 mm at 0.08 m/s, the grip ramped over 10 ms
    out = model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08 * min(1.0, (k + 1) / 10)})
    mu.append(out["pull_force"] / (2 * 12250.0))            # Eq. 1
print(f"mu_bar = {np.mean(mu[-350:]):.4f}")                 # over the last 20 % of the draw, as the demo
