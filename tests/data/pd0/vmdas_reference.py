"""Decodes a VmDAS PD0 file with dolfyn (an independent reader) and writes, per
ensemble, what the tests compare this tool's navigation-block reader with: the
ensemble's clock, and the last GNSS fix before its ping as VmDAS's block 0x2000 states
it (its UTC time, latitude and longitude in degrees, dolfyn's float32). The block's
flags are not written: dolfyn keeps the digits of their binary form in a float, which
rounds them.
Run: python vmdas_reference.py FILE.ENX > FILE.dolfyn_nav.csv  (dolfyn 1.3.0)."""
import contextlib, io, sys, warnings
import dolfyn

warnings.filterwarnings("ignore")
with contextlib.redirect_stdout(io.StringIO()):
    ds = dolfyn.read(sys.argv[1])
seconds = lambda t: t.astype("datetime64[ns]").astype("int64") / 1e9
time_s, fix_s = seconds(ds.time.values), seconds(ds.time_gps.values)
print("time_s,fix_time_s,latitude_deg,longitude_deg")
for k in range(len(time_s)):
    print(f"{time_s[k]:.3f},{fix_s[k]:.4f},{ds.latitude_gps.values[k]!r},"
          f"{ds.longitude_gps.values[k]!r}")
