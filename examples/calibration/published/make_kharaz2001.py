"""Write the Kharaz, Gorham & Salman (2001) oblique-impact data of this folder (SOURCE.md).

The numbers below are copied digit for digit from MFiX's DEM05 verification test,
tests/dem/DEM05/write_usr0.f of the GitHub mirror CurtinIDS/mfix at commit
aa5da900933766e158dd4188220765689855bde7 (identical in soufiane92/MFiX-21.3.2 at
e8a0d92f47910deaf2a20b1365aeb1af2adc2c5f). MFiX's comments say they were read off Figures 6 and
7(b) of Di Renzo & Di Maio (2004), which replot Kharaz et al.'s measurements. Nothing here is
measured anew; the only changes are the sign of the tangential restitution (perga's
beta = -u_t'/u_t) and, in the combined file, the pairing of the two figures' points (SOURCE.md).

    python examples/calibration/published/make_kharaz2001.py          # write the CSVs here
    python examples/calibration/published/make_kharaz2001.py --check  # and print the checks
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

HERE = Path(__file__).resolve().parent

# MFiX write_usr0.f, WRITE_EXP_ALPHA ("Data taken from Figure 7(b) of Di Renzo and Di Maio"):
# angle of incidence from the normal (deg), rebound angle of the centre from the normal (deg).
REBOUND_INCIDENCE = [0.2397, 2.2945, 4.2922, 9.9429, 20.5594, 30.3767, 39.6233, 49.7831, 60.0571]
REBOUND_ANGLE = [0.1194, 1.7630, 2.9577, 6.6917, 12.3645, 21.7809, 32.5455, 45.1051, 57.3652]

# MFiX write_usr0.f, WRITE_EXP_COEFF ("Data taken from Figure 6 of Di Renzo and Di Maio"):
# angle of incidence (deg), tangential restitution of the centre e_t = u_t'/u_t (positive).
COEFF_INCIDENCE = [2.0275, 3.9282, 9.6304, 20.0845, 30.2218, 39.3031, 49.5459, 59.8416]
COEFF_ET = [0.7938, 0.7450, 0.6728, 0.5964, 0.6883, 0.7719, 0.8469, 0.9019]

# Lethe's own digitisation (chaos-polymtl/lethe, examples/dem/3d-oblique-wall-impact/
# oblique_wall_impact_postprocessing.py at 255b519263fbb22f758d40763a12290296d53200), used
# only to gauge the digitisation error (its PR #881 says the example derives from MFiX DEM05).
LETHE_REBOUND_INCIDENCE = [0.016, 2.15, 4.096, 9.826, 20.567, 30.29, 39.535, 49.747, 60.208]
LETHE_REBOUND_ANGLE = [0.074, 1.733, 2.962, 6.518, 12.208, 21.67, 32.613, 45.125, 57.474]
LETHE_COEFF_INCIDENCE = [1.84, 3.703, 9.496, 20.012, 30.127, 39.382, 49.694, 60.02]
LETHE_COEFF_ET = [0.79344, 0.74533, 0.67257, 0.59691, 0.68756, 0.77148, 0.84761, 0.90142]

ANGLE = "granules.placement.angle [deg]"
THETA_R = "shot_rebound_angle_centre [deg]"
BETA = "shot_tangential_restitution_centre"
SLIDING = 30.0
"""deg: the smallest angle of incidence kept in kharaz2001_sliding.csv (SOURCE.md)."""


def _write(path: Path, header: list[str], rows: list[list[str]]) -> None:
    with path.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(rows)
    print(f"wrote {path.name} ({len(rows)} rows)")


def write(folder: Path) -> None:
    # Each figure with its own abscissae, exactly as transcribed.
    rebound = zip(REBOUND_INCIDENCE, REBOUND_ANGLE, strict=True)
    _write(
        folder / "kharaz2001_rebound_angle.csv",
        [ANGLE, THETA_R],
        [[f"{a:.4f}", f"{r:.4f}"] for a, r in rebound],
    )
    _write(
        folder / "kharaz2001_tangential_restitution.csv",
        [ANGLE, BETA],
        [[f"{a:.4f}", f"{-e:.4f}"] for a, e in zip(COEFF_INCIDENCE, COEFF_ET, strict=True)],
    )
    # Combined: the two figures' points paired in order (the ~0 deg rebound point has no e_t
    # partner and is left out); the angle is the mean of the two digitised abscissae.
    rows = []
    for a1, r, a2, e in zip(
        REBOUND_INCIDENCE[1:], REBOUND_ANGLE[1:], COEFF_INCIDENCE, COEFF_ET, strict=True
    ):
        rows.append([f"{(a1 + a2) / 2:.2f}", f"{r:.4f}", f"{-e:.4f}"])
    _write(folder / "kharaz2001.csv", [ANGLE, THETA_R, BETA], rows)
    # The rows where a sphere slides throughout (above 30°, SOURCE.md): a rigid disc's too.
    sliding = [row for row in rows if float(row[0]) >= SLIDING]
    _write(folder / "kharaz2001_sliding.csv", [ANGLE, THETA_R, BETA], sliding)


def check() -> None:
    """Consistency checks quoted in SOURCE.md (derived here, not data)."""
    print("\npaired points: |dx| between figures, implied e_n = e_t tan(th_i)/tan(th_r)")
    for a1, r, a2, e in zip(
        REBOUND_INCIDENCE[1:], REBOUND_ANGLE[1:], COEFF_INCIDENCE, COEFF_ET, strict=True
    ):
        a = math.radians((a1 + a2) / 2)
        print(
            f"  {a1:8.4f} {a2:8.4f}  dx={abs(a1 - a2):.3f}  e_n(mean x)="
            f"{e * math.tan(a) / math.tan(math.radians(r)):.3f}  e_n(own x)="
            f"{e * math.tan(math.radians(a2)) / math.tan(math.radians(r)):.3f}"
        )
    print("\nsliding branch: mu(1+e) = (1 - e_t) tan(th_i)")
    k = [
        (1 - e) * math.tan(math.radians(a))
        for a, e in zip(COEFF_INCIDENCE, COEFF_ET, strict=True)
        if a > 32.5
    ]
    for v in k:
        print(f"  {v:.4f}")
    mean = sum(k) / len(k)
    sd = math.sqrt(sum((v - mean) ** 2 for v in k) / (len(k) - 1))
    print(f"  mean {mean:.4f} sd {sd:.4f} -> mu = {mean / 1.98:.4f} at e = 0.98")
    print("\nMFiX vs Lethe digitisation, max |difference|")
    for name, a, b in [
        ("rebound incidence", REBOUND_INCIDENCE, LETHE_REBOUND_INCIDENCE),
        ("rebound angle", REBOUND_ANGLE, LETHE_REBOUND_ANGLE),
        ("e_t incidence", COEFF_INCIDENCE, LETHE_COEFF_INCIDENCE),
        ("e_t", COEFF_ET, LETHE_COEFF_ET),
    ]:
        print(f"  {name:18s} {max(abs(x - y) for x, y in zip(a, b, strict=True)):.4f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="print the consistency checks")
    parser.add_argument("-o", "--output", type=Path, default=HERE, help="folder (default: here)")
    args = parser.parse_args()
    write(args.output)
    if args.check:
        check()
