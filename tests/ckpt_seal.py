"""The seal of a sphseg checkpoint (src/output/checkpoint.h), for tests that change
a checkpoint on purpose with h5py and must seal it again so that sphseg's
reader, not its checksum, meets the change: the sum over the little-endian
8-byte words w_i past the 512-byte user block (i from 1, the last word
zero-padded) of splitmix64's finaliser of w_i + i * 0x9E3779B97F4A7C15, mod
2^64, written with the file size at bytes 16-31 of the user block; then the
seal's own check at bytes 48-55: h = 0, h = mix(h ^ (v_k + (k + 1) * G)) over
the words v_0..v_5 at bytes 0-47, 1 where that gives 0 (0 there marks a
legacy seal, one written before the check existed)."""
import numpy as np

M64 = (1 << 64) - 1
GOLDEN = 0x9E3779B97F4A7C15


def mix(z):
    """splitmix64's finaliser, on a Python int mod 2^64."""
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M64
    return z ^ (z >> 31)


def seal_check(head):
    """The check word of a seal whose first 48 bytes are head."""
    h = 0
    for k in range(6):
        h = mix(h ^ ((int.from_bytes(head[8 * k:8 * k + 8], "little") + (k + 1) * GOLDEN) & M64))
    return h or 1


def reseal(path, legacy=False):
    """Seal path again (size, checksum, check; legacy: check 0, as written
    before the check existed)."""
    with open(path, "r+b") as f:
        data = f.read()
        body = data[512:] + b"\0" * (-(len(data) - 512) % 8)
        w = np.frombuffer(body, dtype="<u8")
        with np.errstate(over="ignore"):
            i = np.arange(1, len(w) + 1, dtype=np.uint64)
            z = w + i * np.uint64(GOLDEN)
            z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
            z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
            z = z ^ (z >> np.uint64(31))
            h = int(z.sum(dtype=np.uint64))
        head = bytearray(data[:48])
        head[16:32] = len(data).to_bytes(8, "little") + h.to_bytes(8, "little")
        f.seek(0)
        f.write(bytes(head) + (0 if legacy else seal_check(head)).to_bytes(8, "little"))
