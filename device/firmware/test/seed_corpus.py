"""Seed inputs for the fuzz target (test/fuzz_rx.c) from the shared vectors.

Usage: seed_corpus.py vectors/frames.json OUT_DIR. Raw-mode seeds carry each vector's
byte stream; framed-mode seeds are short sessions (Hello, Blocks, Heartbeats, Stop)
built from the vectors' bodies, so the fuzzer starts deep in the state machine.
"""

import json
import sys
from pathlib import Path


def cobs_decode(data: bytes) -> bytes:
    out, i = bytearray(), 0
    while i < len(data):
        code = data[i]
        out += data[i + 1:i + code]
        if code < 255 and i + code < len(data):
            out.append(0)
        i += code
    return bytes(out)


def main(vectors: str, out_dir: str) -> None:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = json.loads(Path(vectors).read_text())
    bodies = []
    for i, row in enumerate(rows):
        stream = bytes.fromhex(row["hex"])
        (out / f"raw-{i:04d}").write_bytes(bytes([i % 8, 40]) + stream)
        if row["reencode"] and stream.count(0) == 1:
            bodies.append(cobs_decode(stream[:-1])[:-4])  # body without its CRC
    hello = [b for b in bodies if b[1] == 0x01]
    blocks = [b for b in bodies if b[1] == 0x02]
    beats = [b for b in bodies if b[1] in (0x03, 0x04)]
    for i in range(min(64, len(blocks))):
        session = [hello[i % len(hello)], *blocks[i:i + 4], beats[i % len(beats)]]
        records = b"".join(len(b).to_bytes(2, "little") + bytes([i % 50]) + b for b in session)
        (out / f"session-{i:03d}").write_bytes(bytes([0x80 | (i % 8), i]) + records)


if __name__ == "__main__":
    main(*sys.argv[1:])
