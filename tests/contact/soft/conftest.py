"""Soft-kernel tests run on one numba thread unless a test asks for more.

The systems here are small (≤ 400 granules), where threads only add launch overhead, and a busy
machine (another job on the second core) makes two-thread barriers slow by orders of magnitude.
"""

import numba

numba.set_num_threads(1)
