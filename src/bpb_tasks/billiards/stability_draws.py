"""The stability perturbations in compiled code: the draws of ``random.Random(text).random()``,
to the bit, without a Python call per draw, and the perturbed copies built from them
(:func:`perturb`, :func:`~bpb_tasks.billiards.stability.perturbation_arrays` without the numpy
calls).

CPython seeds its Mersenne Twister (MT19937) from a string by ``init_by_array`` on the 32-bit
words of ``int.from_bytes(text + sha512(text))`` and builds each float from two 32-bit outputs
(``(a >> 5) * 2**26 + (b >> 6)``, times ``2**-53``). :func:`seed_key` computes those words in
Python (one hash); :func:`random_draws` runs the seeding and the generator on them (a test
compares with :class:`random.Random`). Words are kept in int64 and masked to 32 bits, so no
product overflows.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np

from bpb_tasks.simulators.analytic.kernel_predict import Arr
from bpb_tasks.simulators.analytic.kernel_roots import jit

N, M = 624, 397
MASK = 0xFFFFFFFF
TWO_PI = 2 * math.pi


def seed_key(text: str) -> np.ndarray:
    """The ``init_by_array`` key of ``random.Random(text)``: 32-bit words, least significant
    first."""
    data = text.encode()
    number = int.from_bytes(data + hashlib.sha512(data).digest(), "big")
    words = (number.bit_length() + 31) // 32 or 1
    return np.frombuffer(number.to_bytes(4 * words, "little"), dtype="<u4").astype(np.int64)


@jit
def perturb(
    key: Arr, samples: int, centres: Arr, velocities: Arr, delta: float, cue: int, kick: float
) -> tuple[Arr, Arr]:
    """The ``(samples, n, 2)`` positions and velocities of the copies of ``n`` balls at
    ``centres`` moving at ``velocities``, from the draws of a generator seeded with ``key``
    (:func:`~bpb_tasks.billiards.stability_draws.random_draws`), ``n + 1`` per copy: ball ``j``
    moved by ``delta`` at angle ``2 pi`` times draw ``j``, the cue ball (index ``cue``, -1
    without one) kicked by ``kick`` at angle ``2 pi`` times draw ``n``. The numpy operations of
    ``perturbation_arrays`` element by element."""
    n = centres.shape[0]
    angles = random_draws(key, samples * (n + 1))
    pos = np.empty((samples, n, 2))
    vel = np.empty((samples, n, 2))
    for k in range(samples):
        row = k * (n + 1)
        for j in range(n):
            angle = angles[row + j] * TWO_PI
            pos[k, j, 0] = centres[j, 0] + delta * np.cos(angle)
            pos[k, j, 1] = centres[j, 1] + delta * np.sin(angle)
            vel[k, j, 0], vel[k, j, 1] = velocities[j, 0], velocities[j, 1]
        if cue >= 0:
            angle = angles[row + n] * TWO_PI
            vel[k, cue, 0] += kick * np.cos(angle)
            vel[k, cue, 1] += kick * np.sin(angle)
    return pos, vel


@jit
def random_draws(key: Arr, count: int) -> Arr:
    """The first ``count`` values of ``random()`` from a generator seeded with ``key``."""
    mt = _seeded(key)
    out = np.empty(count)
    index = N
    for c in range(count):
        if index >= N:
            _twist(mt)
            index = 0
        a = _temper(mt[index]) >> 5
        index += 1
        if index >= N:
            _twist(mt)
            index = 0
        b = _temper(mt[index]) >> 6
        index += 1
        out[c] = (a * 67108864.0 + b) * (1.0 / 9007199254740992.0)
    return out


@jit
def _seeded(key: Arr) -> Arr:
    """``init_genrand(19650218)`` then ``init_by_array(key)``."""
    mt = np.empty(N, dtype=np.int64)
    mt[0] = 19650218
    for i in range(1, N):
        mt[i] = (1812433253 * (mt[i - 1] ^ (mt[i - 1] >> 30)) + i) & MASK
    i, j = 1, 0
    for _ in range(max(N, key.shape[0])):
        mt[i] = ((mt[i] ^ ((mt[i - 1] ^ (mt[i - 1] >> 30)) * 1664525)) + key[j] + j) & MASK
        i, j = i + 1, j + 1
        if i >= N:
            mt[0], i = mt[N - 1], 1
        if j >= key.shape[0]:
            j = 0
    for _ in range(N - 1):
        mt[i] = ((mt[i] ^ ((mt[i - 1] ^ (mt[i - 1] >> 30)) * 1566083941)) - i) & MASK
        i += 1
        if i >= N:
            mt[0], i = mt[N - 1], 1
    mt[0] = 0x80000000
    return mt


@jit
def _twist(mt: Arr) -> None:
    """The next block of 624 words."""
    for k in range(N - M):
        mt[k] = _mixed(mt[k + M], mt[k], mt[k + 1])
    for k in range(N - M, N - 1):
        mt[k] = _mixed(mt[k + M - N], mt[k], mt[k + 1])
    mt[N - 1] = _mixed(mt[M - 1], mt[N - 1], mt[0])


@jit
def _mixed(far: int, word: int, following: int) -> int:
    y = (word & 0x80000000) | (following & 0x7FFFFFFF)
    return far ^ (y >> 1) ^ (0x9908B0DF if y & 1 else 0)


@jit
def _temper(word: int) -> int:
    y = word
    y ^= y >> 11
    y ^= (y << 7) & 0x9D2C5680
    y ^= (y << 15) & 0xEFC60000
    y ^= y >> 18
    return y
