#!/usr/bin/env python3
"""Writes a seed corpus of valid wire packets for decoder_fuzz (docs/hardware.md "Fuzzing").

Each seed is one fuzz input: a first byte that picks the chunk size the target feeds the decoder in,
then bytes as they come off the port (COBS-encoded packets with their CRC and 0x00 delimiters, per
/work/shared/PROTOCOL.md). Valid packets let the fuzzer start past the CRC check instead of having to
find a matching CRC by chance. Usage: fuzz/make_seed_corpus.py DIR
"""
import os
import struct
import sys


def crc16_ccitt_false(data: bytes) -> int:
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def cobs_encode(data: bytes) -> bytes:
    out = bytearray([0])
    code_index, code = 0, 1
    for byte in data:
        if byte == 0:
            out[code_index] = code
            code_index, code = len(out), 1
            out.append(0)
            continue
        out.append(byte)
        code += 1
        if code == 0xFF:
            out[code_index] = code
            code_index, code = len(out), 1
            out.append(0)
    out[code_index] = code
    return bytes(out)


def wire(body: bytes) -> bytes:
    return cobs_encode(body + struct.pack("<H", crc16_ccitt_false(body))) + b"\x00"


def header(packet_type: int, sequence: int, version: int = 1) -> bytes:
    return struct.pack("<BBH", packet_type, version, sequence & 0xFFFF)


def frame(sequence: int, units: int, time_us: int = 0, flags: int = 0) -> bytes:
    body = header(0x01, sequence) + struct.pack("<IBB", (time_us or 1000 * sequence) & 0xFFFFFFFF, units, flags)
    for k in range(units):
        r1 = 0xFFFFFFFF if k == 0 else (0 if k == 1 else 3_400_000 + 1000 * k)
        body += struct.pack("<II", r1, 3_400_000 - 1000 * k)
    return wire(body)


def hello(sequence: int, units: int) -> bytes:
    return wire(header(0x02, sequence) + struct.pack("<HBBHHI", 0x0100, units, 0, 1000, 0, 3_400_000))


def main() -> None:
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out_dir = sys.argv[1]
    os.makedirs(out_dir, exist_ok=True)
    seeds = {
        "hello_then_frames_20": hello(0, 20) + b"".join(frame(s, 20) for s in range(3)),
        "frame_1_unit": frame(7, 1, flags=1),
        "frame_62_units": frame(9, 62, flags=3),
        "frames_9_units_gap": frame(1, 9) + frame(3, 9) + frame(2, 9),
        "motor_and_stream": wire(header(0x81, 5) + struct.pack("<hBB", -12345, 3, 0))
        + wire(header(0x82, 1) + b"\x01"),
        "unknown_type_and_version": wire(header(0x33, 0) + b"\xab\xcd") + wire(header(0x02, 0, version=2) + bytes(12)),
        "garbage_between": b"\x13\x37\x42" + frame(4, 20) + b"\xff" * 40 + b"\x00" + frame(5, 20),
        "wrapping_sequence": frame(65535, 4, time_us=0xFFFFFC18) + frame(0, 4, time_us=0),
    }
    for index, (name, data) in enumerate(sorted(seeds.items())):
        chunk_selector = bytes([(37 * index + 5) % 256])  # various chunk sizes
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(chunk_selector + data)
    print(f"{len(seeds)} seeds in {out_dir}")


if __name__ == "__main__":
    main()
