"""Plots SPEC 3's S2 (the converter under 12 N·m on the crank and 800 N·m on the shaft)
from Python: the crank's and the shaft's speeds, the clutch torques and the mode, with
the diode's events marked. Writes s2.png (matplotlib's Agg backend, no display needed).

    python python/examples/s2_plot.py [OUT.png] [T_END]
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import structomat  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "s2.png"
t_end = float(sys.argv[2]) if len(sys.argv) > 2 else 1.0

r = structomat.run("ccc-s2", t_end=t_end)
c, ev = r.columns, r.events
t = c["t"]

fig, ax = plt.subplots(3, 1, sharex=True, figsize=(9, 8))
ax[0].plot(t, c["omega1"], label="crank ω₁")
ax[0].plot(t, c["shaft_speed"], label="shaft")
ax[0].set_ylabel("speed, rad/s")
ax[0].legend(loc="upper left")
ax[1].plot(t, c["c6"], label="clutch 6")
ax[1].plot(t, c["c8"], label="clutch 8")
ax[1].set_ylabel("clutch torque, N·m")
ax[1].legend(loc="upper left")
ax[2].step(t, c["mode_code"], where="post")
ax[2].set_ylabel("mode code")
ax[2].set_xlabel("t, s")
for x in ev["time"][1:]:
    for a in ax:
        a.axvline(x, color="0.85", lw=0.5, zorder=0)
s = r.summary
fig.suptitle(f"S2: {s['event_count']} events, audit residual {s['audit']['residual']:.2e} J "
             f"of {s['audit']['motor_work']:.1f} J motor work")
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}: {len(r)} rows, final mode {s['mode']}")
