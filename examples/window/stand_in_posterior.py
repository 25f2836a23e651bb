"""A stand-in for a calibration of the bee-bread separator's comb and contact: a posterior
sample (posterior.parquet, as ``perga calibrate`` writes it) for ``perga window --posterior``
until measured release and rebound data give a real one.

The granule-steel restitution e ~ N(0.70, 0.03²) within [0.4, 0.95] (the paper's 0.6-0.8 as
about ±3 sd) and the detachment energy E_c log-normal about 0.06 J, σ = ln 1.2 (about 18 %; an
assumption's spread), independent; 4,000 draws, seed 0.

    python examples/window/stand_in_posterior.py [-o DIR]
"""

import argparse
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

DRAWS = 4000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=Path("stand-in-calibration"))
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    e = 0.70 + 0.03 * rng.standard_normal(DRAWS)
    energy = 0.06 * np.exp(np.log(1.2) * rng.standard_normal(DRAWS))
    keep = (e >= 0.4) & (e <= 0.95)
    args.output.mkdir(parents=True, exist_ok=True)
    table = pa.table(
        {
            "contacts.beebread-steel.restitution": e[keep],
            "materials.beebread.detachment_energy": energy[keep],
        }
    )
    pq.write_table(table, args.output / "posterior.parquet")
    print(f"{table.num_rows} draws -> {args.output / 'posterior.parquet'}")


if __name__ == "__main__":
    main()
