"""LAMMPS side of the soft-contact benchmark: dense settled 2-D bed, particle-steps per second.

Same inputs as ``benchmarks/soft_bed.py`` (design §8): 2-D discs, linear spring-dashpot
k_n = 1e6 N/m, k_t = 2/7 k_n, e = 0.7, friction 0.5, gravity −9.81 m/s² in the plane, in a box
(floor and two side walls, granular walls of the same law) √n granules wide, built on a square
lattice of pitch 2 r_max·1.001 with the same jitter, dt = t_c/50 of the granule-granule contact
(t_c of the force-clamped law perga uses, so that both advance the same simulated time per
step). LAMMPS: Debian's ``lmp`` (``pair_style gran/hooke/history``, ``fix wall/gran
hooke/history``, ``fix enforce2d``), one process, one thread. Its normal force is not clamped
(contact ends at zero overlap), so its damping is ζ = damping_ratio(e, "overlap"), as
γ_n = 2ζ√(k_n/m_eff) with m_eff = m/2 for pairs (same m) and m at walls.

Granules: by default r = 2.5 mm and m = 0.16 g, all equal (the brief); ``--soft-bed`` takes
soft_bed.py's r = 2 mm ± 5 % and sphere masses of density 1400 kg/m³ instead. Masses are given
to LAMMPS as per-atom densities: in 2-D, LAMMPS 2021's ``read_data``/``set density`` uses the
sphere volume 4/3 π r³ (``set density/disc`` the area π r²); the script checks the total mass
LAMMPS reports. LAMMPS keeps the sphere moment 2/5 m r² in 2-D (a disc has 1/2 m r²).

Timing: relax (--relax steps, speed capped at 0.2 m/s by ``fix nve/limit``, ``fix viscous``
with a 0.5 ms drag time: the jittered lattice overlaps), then --settle-time of simulated time
without them (gravity collapse), then --repeats runs of --steps steps; each run's "Loop time"
gives particle-steps/s; the median is printed, with wall seconds per simulated second. Check the
printed contacts per granule (about 3 when settled). Also the restitution of one disc on a
``fix wall/gran`` plane at 1 and 10 m/s. Inputs go to a temporary directory (templates in
benchmarks/lammps/).

    python benchmarks/lammps_bed.py                       # 1,000 and 10,000 granules
    python benchmarks/lammps_bed.py --sizes 1000 --steps 500   # smoke
    python benchmarks/lammps_bed.py --soft-bed            # soft_bed.py's granules
"""

import argparse
import math
import re
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from perga.analytic.contact import LinearSpringDashpot, damping_ratio

TEMPLATES = Path(__file__).with_name("lammps")
K_N = 1e6
K_T = 2.0 / 7.0 * K_N
E = 0.7
FRICTION = 0.5
LOOP = re.compile(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")


def lammps_binary() -> str:
    for name in ("lmp", "lmp_serial", "lmp_mpi"):
        path = shutil.which(name)
        if path:
            return path
    raise SystemExit("no LAMMPS binary found (apt-get install lammps)")


def run_lammps(binary: str, script: Path, workdir: Path, variables: dict[str, object]) -> str:
    cmd = [binary, "-in", str(script), "-log", str(workdir / "log.lammps"), "-screen", "none"]
    for key, value in variables.items():
        cmd += ["-var", key, str(value)]
    env = {"OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"}
    proc = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
    log = (workdir / "log.lammps").read_text()
    if proc.returncode != 0 or "ERROR" in log:
        raise SystemExit(f"LAMMPS failed ({proc.returncode}):\n{log[-2000:]}\n{proc.stderr}")
    return log


def granules(n: int, soft_bed: bool, seed: int = 0):
    """Radii, masses and lattice positions (soft_bed.py's construction), box width."""
    rng = np.random.default_rng(seed)
    if soft_bed:
        r = 2e-3 * rng.uniform(0.95, 1.05, n)
        m = 1400.0 * 4.0 / 3.0 * math.pi * r**3
    else:
        r = np.full(n, 2.5e-3)
        m = np.full(n, 1.6e-4)
    cols = math.ceil(math.sqrt(n))
    pitch = 2.0 * r.max() * 1.001
    idx = np.arange(n)
    x = np.column_stack(
        [(idx % cols + 0.5) * pitch, (idx // cols + 0.5) * pitch + 1e-4 * rng.standard_normal(n)]
    )
    x[:, 0] += 0.1 * pitch * rng.uniform(-1, 1, n)
    return r, m, x, cols * pitch


def write_data(path: Path, r, m, x, width: float) -> None:
    """atom_style sphere data file; density = m/(4/3 π r³), LAMMPS's 2-D convention (checked)."""
    rho = m / (4.0 / 3.0 * math.pi * r**3)
    r_max = float(r.max())
    height = 3.0 * (float(x[:, 1].max()) + r_max)
    lines = [
        "perga dense bed (benchmarks/lammps_bed.py)",
        "",
        f"{len(r)} atoms",
        "1 atom types",
        "",
        f"0.0 {width:.17g} xlo xhi",
        f"{-r_max:.17g} {height:.17g} ylo yhi",
        f"{-r_max:.17g} {r_max:.17g} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    lines += [
        f"{i + 1} 1 {2.0 * r[i]:.17g} {rho[i]:.17g} {x[i, 0]:.17g} {x[i, 1]:.17g} 0.0"
        for i in range(len(r))
    ]
    path.write_text("\n".join(lines) + "\n")


def bed(binary: str, n: int, args, workdir: Path) -> None:
    r, m, x, width = granules(n, args.soft_bed)
    m_pair = float(m.min()) / 2.0  # smallest pair: shortest contact
    t_c = LinearSpringDashpot.from_stiffness(K_N, E, m_pair, "force").duration
    dt = t_c / 50.0
    zeta = damping_ratio(E, "overlap")
    m_typ = float(np.median(m))
    data = workdir / f"bed{n}.data"
    write_data(data, r, m, x, width)
    variables = {
        "data": data,
        "width": f"{width:.17g}",
        "kn": K_N,
        "kt": K_T,
        "gn": 2.0 * zeta * math.sqrt(K_N / (m_typ / 2.0)),
        "gnw": 2.0 * zeta * math.sqrt(K_N / m_typ),
        "mu": FRICTION,
        "dt": f"{dt:.17g}",
        "skin": 0.2 * float(r.min()),
        "visc": m_typ / 5e-4,  # drag time 0.5 ms
        "xmax": f"{0.2 * dt:.17g}",  # relax: speed capped at 0.2 m/s
        "relax": args.relax,
        "settle": math.ceil(args.settle_time / dt),
        "steps": args.steps,
        "repeats": args.repeats,
    }
    log = run_lammps(binary, TEMPLATES / "bed.in", workdir, variables)
    total = float(re.search(r"^TOTAL_MASS (\S+)", log, re.M).group(1))
    settled = re.search(r"^SETTLED_KE (\S+) CONTACTS (\S+)", log, re.M)
    ke, contacts = float(settled.group(1)), float(settled.group(2))
    loops = [(float(t), int(s), int(a)) for t, _, s, a in LOOP.findall(log)][3:]
    rates = [a * s / t for t, s, a in loops]
    rate = statistics.median(rates)
    wall_per_sim = n / (rate * dt)
    print(
        f"n = {n}: dt = {dt:.3e} s (t_c = {t_c:.3e} s), mass check {total / m.sum() - 1:+.1e}, "
        f"settled KE {ke:.2e} J, {contacts / n:.2f} contacts per granule (walls included)\n"
        f"  particle-steps/s: {', '.join(f'{x / 1e6:.2f}' for x in rates)} M "
        f"-> median {rate / 1e6:.2f} M; wall s per simulated s: {wall_per_sim:.0f}"
    )


def wall_restitution(binary: str, workdir: Path) -> None:
    r, m = 2.5e-3, 1.6e-4
    zeta = damping_ratio(E, "overlap")
    wall = LinearSpringDashpot.from_stiffness(K_N, E, m, "overlap")
    dt = LinearSpringDashpot.from_stiffness(K_N, E, m / 2.0, "force").duration / 50.0
    for v0 in (1.0, 10.0):
        variables = {
            "r": r,
            "rho_area": f"{m / (math.pi * r * r):.17g}",
            "v0": v0,
            "kn": K_N,
            "kt": K_T,
            "gnw": 2.0 * zeta * math.sqrt(K_N / m),
            "dt": f"{dt:.17g}",
            "nsteps": math.ceil(3.0 * wall.duration / dt) + 10,
        }
        log = run_lammps(binary, TEMPLATES / "wall_e.in", workdir, variables)
        mass = float(re.search(r"^MASS (\S+)", log, re.M).group(1))
        vy = float(re.search(r"^VY (\S+)", log, re.M).group(1))
        print(f"wall impact at {v0:g} m/s: e = {vy / v0:.4f} (target {E}), mass {mass:.6g} kg")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--steps", type=int, default=2000, help="steps per timed run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--relax", type=int, default=20000, help="steps with fix viscous")
    parser.add_argument(
        "--settle-time", type=float, default=0.026, help="simulated s after the drag, s"
    )
    parser.add_argument("--soft-bed", action="store_true", help="soft_bed.py's granules")
    args = parser.parse_args()
    binary = lammps_binary()
    version = subprocess.run([binary, "-h"], capture_output=True, text=True).stdout
    print(f"{binary}: {version.splitlines()[1].strip() if version else '?'}")
    with tempfile.TemporaryDirectory(prefix="perga-lammps-") as tmp:
        workdir = Path(tmp)
        wall_restitution(binary, workdir)
        for n in args.sizes:
            bed(binary, n, args, workdir)


if __name__ == "__main__":
    main()
