"""The local cluster's workers: a study started from a script that imported numba before it
(a benchmark, a user's script using the API) runs on workers whose numba can still compile after
its threads were launched. Dask's Nanny applies a worker's ``env`` after the spawned process has
imported the script, numba with it; a ``NUMBA_NUM_THREADS`` there differing from the count
numba read at import made every later compile fail ("Cannot set NUMBA_NUM_THREADS to a different
value once the threads have been launched"): all 18 rigid runs of a convergence benchmark."""

import subprocess
import sys
from pathlib import Path

SCRIPT = '''
import numba  # before the workers apply their environment, as a script that uses perga may

from perga.studies.executor import dask_client


def probe():
    """What a run does: numba on one thread (which launches its threads), then a compile."""
    numba.set_num_threads(1)

    @numba.njit
    def twice(x):
        return 2 * x

    return twice(2), numba.get_num_threads()


if __name__ == "__main__":
    with dask_client(workers=1) as client:
        print(list(client.run(probe).values()))
'''


def test_workers_compile_after_their_threads_were_launched(tmp_path: Path) -> None:
    script = tmp_path / "study.py"
    script.write_text(SCRIPT)
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "[(4, 1)]", done.stdout
