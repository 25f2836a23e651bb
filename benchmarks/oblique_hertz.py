"""Issue 19: single oblique Hertz impacts of a soft granule (E = 5 MPa, ν = 0.35, ρ = 1300
kg/m³, r = 3 mm, 3.9 m/s, f = 0.3, t_c/50) on a flat wall, a resting twin and a kinematic
polygon's face, angles 5-85°: the energy lost and the booked dissipation's error, both over the
impact's energy (docs/dev/validation.md, "The Hertz tangential spring keeps its energy"). The
impact itself is the test's (``tests/contact/soft/test_kernel_energy.py::_oblique``).

    python benchmarks/oblique_hertz.py          # ~10 s
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.contact.soft.test_kernel_energy import _oblique


def main() -> None:
    for target in ("wall", "pair", "polygon"):
        for e in (0.7, 1.0):
            rows = [(angle, *_oblique(target, e, angle)) for angle in range(5, 90, 10)]
            text = ", ".join(f"{a}°: lost {lost:.3g}, error {err:+.1e}" for a, err, lost in rows)
            print(f"{target}, e = {e}: {text}")


if __name__ == "__main__":
    main()
