"""Decodes PD0 files with dolfyn (an independent reader) and writes, per ensemble, what
the tests compare this tool's reader with: the clock, the bottom-track velocity as
recorded (m/s, NaN where dolfyn reads none), and the same turned into the instrument's
axes by dolfyn's own rotations, where it can turn the file's frame.
Run: python dolfyn_reference.py FILE.PD0 > FILE.dolfyn.csv  (dolfyn 1.3.0)."""
import contextlib, io, sys, warnings
import numpy as np
import dolfyn

warnings.filterwarnings("ignore")
path = sys.argv[1]
with contextlib.redirect_stdout(io.StringIO()):
    ds = dolfyn.read(path)
frame = ds.coord_sys
raw = ds["vel_bt"].values.copy()
inst = np.full((3, raw.shape[1]), np.nan)
try:
    if frame != "inst":
        with contextlib.redirect_stdout(io.StringIO()):
            dolfyn.rotate2(ds, "inst", inplace=True)
    inst = ds["vel_bt"].values[:3]
except Exception as e:  # dolfyn turns no ship frame back
    print(f"# dolfyn does not turn {frame} into inst: {e}", file=sys.stderr)
time_s = (ds.time.values.astype("datetime64[ns]").astype("int64") / 1e9)
print("time_s,v1_m_s,v2_m_s,v3_m_s,v4_m_s,x_m_s,y_m_s,z_m_s,heading_deg,pitch_deg,roll_deg")
for k in range(raw.shape[1]):
    row = [f"{time_s[k]:.3f}"] + [f"{v:.4f}" for v in raw[:, k]] + [f"{v:.6f}" for v in inst[:, k]]
    row += [f"{ds[n].values[k]:.2f}" for n in ("heading", "pitch", "roll")]
    print(",".join(row))
