"""An independent least-squares fit of the DVL's scale and heading misalignment to the
GNSS fixes recorded in the same WinRiver PD0 log, the model `calibrate --fixes` fits:
each fix = a start position + g * the DVL's displacement, where the displacement is the
bottom track (dolfyn's decode, ship coordinates, its sign turned to the boat's) turned
to north and east by the log's heading and summed by the trapezoidal rule from the
piece's first ping, read at the fix's time, and g = k exp(i psi) is one complex number
(north + i east: k the GNSS's distance over the DVL's; psi how far clockwise, seen from
above, the GNSS's track lies from the DVL's). The GGA sentences are found by a walk of the ensembles' offsets written
here, not this tool's reader; each fix is placed on the log's clock by the median of
its time less its ensemble's. Pieces are cut at gaps over 3.93 s (three times the
median interval, as the tool cuts them); fixes outside a piece are left out.
Run: python gnss_fit.py winriver02.PD0 winriver02.dolfyn.csv > winriver02.gnss_fit.csv
(numpy only)."""
import csv, math, struct, sys
import numpy as np

EARTH_RADIUS_M = 6378137.0


def gga_per_ensemble(path):
    """Each ensemble's GGA (time of day s, latitude, longitude, degrees) or None."""
    data = open(path, "rb").read()
    out, i = [], 0
    while i < len(data) - 4:
        if data[i] != 0x7F or data[i + 1] != 0x7F:
            i += 1
            continue
        size = struct.unpack_from("<H", data, i + 2)[0]
        count = data[i + 5]
        offsets = [struct.unpack_from("<H", data, i + 6 + 2 * k)[0] for k in range(count)]
        ends = sorted(offsets) + [size]
        fix = None
        for o in offsets:
            if struct.unpack_from("<H", data, i + o)[0] != 0x2101:
                continue
            end = ends[ends.index(o) + 1]
            text = data[i + o + 4 : i + end].split(b"\r")[0].decode()
            f = text.split(",")
            if f[0] == "$GPGGA":
                t = int(f[1][:2]) * 3600 + int(f[1][2:4]) * 60 + float(f[1][4:])
                lat = (int(f[2][:2]) + float(f[2][2:]) / 60) * (1 if f[3] == "N" else -1)
                lon = (int(f[4][:3]) + float(f[4][3:]) / 60) * (1 if f[5] == "E" else -1)
                fix = (t, lat, lon)
        out.append(fix)
        i += size + 2
    return out


def main(pd0, decoded):
    rows = list(csv.DictReader(open(decoded)))
    time_s = np.array([float(r["time_s"]) for r in rows]) % 86400.0
    heading = np.radians([float(r["heading_deg"]) for r in rows])
    # Ship coordinates: X starboard, Y forward; bottom track is the bottom's velocity.
    forward = -np.array([float(r["v2_m_s"]) for r in rows])
    starboard = -np.array([float(r["v1_m_s"]) for r in rows])
    north = forward * np.cos(heading) - starboard * np.sin(heading)
    east = forward * np.sin(heading) + starboard * np.cos(heading)
    velocity = north + 1j * east
    fixes = [(k, g) for k, g in enumerate(gga_per_ensemble(pd0)) if g and k < len(rows)]
    behind_s = np.median([g[0] - time_s[k] for k, g in fixes])
    lat0, lon0 = fixes[0][1][1], fixes[0][1][2]
    fix_t = np.array([g[0] - behind_s for _, g in fixes])
    fix_z = np.array(
        [
            complex(
                math.radians(g[1] - lat0) * EARTH_RADIUS_M,
                math.radians(g[2] - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0)),
            )
            for _, g in fixes
        ]
    )
    gap_s = 3 * np.median(np.diff(time_s))
    cuts = [0] + [k for k in range(1, len(time_s)) if time_s[k] - time_s[k - 1] > gap_s]
    columns, targets, pieces = [], [], []
    for p, (a, b) in enumerate(zip(cuts, cuts[1:] + [len(time_s)])):
        t, v = time_s[a:b], velocity[a:b]
        inside = (fix_t >= t[0]) & (fix_t <= t[-1])
        if inside.sum() < 2:
            continue
        summed = np.concatenate([[0], np.cumsum(0.5 * np.diff(t) * (v[1:] + v[:-1]))])
        at = fix_t[inside]
        columns.append(np.interp(at, t, summed.real) + 1j * np.interp(at, t, summed.imag))
        targets.append(fix_z[inside])
        pieces.append(p)
    n = sum(len(c) for c in columns)
    design = np.zeros((n, 1 + len(columns)), complex)
    row = 0
    for p, c in enumerate(columns):
        design[row : row + len(c), 0] = c
        design[row : row + len(c), 1 + p] = 1.0
        row += len(c)
    target = np.concatenate(targets)
    solution, *_ = np.linalg.lstsq(design, target, rcond=None)
    g = solution[0]
    residual = target - design @ solution
    print("fixes,pieces,clock_behind_s,gnss_over_dvl,clockwise_deg,residual_rms_m")
    print(
        f"{n},{len(columns)},{behind_s:.3f},{abs(g):.6f},{math.degrees(np.angle(g)):.4f},"
        f"{math.sqrt(np.mean(np.abs(residual) ** 2)):.4f}"
    )


main(sys.argv[1], sys.argv[2])
