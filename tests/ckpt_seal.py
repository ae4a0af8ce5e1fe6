"""The seal of a sphseg checkpoint (src/checkpoint.h), for tests that change
a checkpoint on purpose with h5py and must seal it again so that sphseg's
reader, not its checksum, meets the change: the sum over the little-endian
8-byte words w_i past the 512-byte user block (i from 1, the last word
zero-padded) of splitmix64's finaliser of w_i + i * 0x9E3779B97F4A7C15, mod
2^64, written with the file size at bytes 16-31 of the user block."""
import numpy as np


def reseal(path):
    with open(path, "r+b") as f:
        data = f.read()
        body = data[512:] + b"\0" * (-(len(data) - 512) % 8)
        w = np.frombuffer(body, dtype="<u8")
        with np.errstate(over="ignore"):
            i = np.arange(1, len(w) + 1, dtype=np.uint64)
            z = w + i * np.uint64(0x9E3779B97F4A7C15)
            z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
            z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
            z = z ^ (z >> np.uint64(31))
            h = int(z.sum(dtype=np.uint64))
        f.seek(16)
        f.write(len(data).to_bytes(8, "little") + h.to_bytes(8, "little"))
