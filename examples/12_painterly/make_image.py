#!/usr/bin/env python3
"""Writes the example's picture and mask (standard library only, no binaries in git):

    python3 make_image.py            # -> lake.png (480×360), lake_mask.png, sun_mask.png

lake.png: an evening sky with a sun over dark hills and a lake with ripples and the sun's
reflection; lake_mask.png: white over the lake (where the field moves the strokes), black
elsewhere (strokes stay put), as in the paper's Fig. 1 where only the water is animated;
sun_mask.png: white in a disc round the sun, for the burning sun of Fig. 17 (scene_sun.json).
"""
import math
import struct
import sys
import zlib

W, H = 480, 360
HORIZON = int(H * 0.55)


def png(path, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def mix(a, b, s):
    return [round(a[k] + (b[k] - a[k]) * s) for k in range(3)]


def pixel(x, y):
    sun = (330, 150)
    if y < HORIZON:
        c = mix((40, 60, 140), (250, 170, 90), (y / HORIZON) ** 1.5)
        d = math.hypot(x - sun[0], y - sun[1])
        if d < 30:
            return (255, 235, 140)
        c = mix(c, (255, 210, 120), max(0.0, 1 - d / 120) ** 2)
        hill = HORIZON - 40 - 25 * math.sin(x / 70.0) - 12 * math.sin(x / 23.0 + 1)
        if y > hill:
            c = mix((30, 55, 40), (20, 35, 30), (y - hill) / 60)
        return c
    s = (y - HORIZON) / (H - HORIZON)
    c = mix((70, 90, 150), (20, 40, 90), s)
    ripple = 0.5 + 0.5 * math.sin(y * 0.9 + 3 * math.sin(x / 40.0))
    c = mix(c, (120, 150, 200), 0.35 * ripple)
    if abs(x - sun[0]) < 40 * (1 - 0.5 * s) and ripple > 0.4:
        c = mix(c, (255, 200, 110), 0.8)
    return c


def main():
    rows = [[v for x in range(W) for v in pixel(x, y)] for y in range(H)]
    png("lake.png", rows)
    png("lake_mask.png", [[255 if y >= HORIZON else 0 for x in range(W) for _ in range(3)] for y in range(H)])
    png("sun_mask.png", [[255 if math.hypot(x - 330, y - 150) < 95 else 0 for x in range(W) for _ in range(3)]
                         for y in range(H)])
    return 0


if __name__ == "__main__":
    sys.exit(main())
