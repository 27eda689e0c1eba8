#!/usr/bin/env python3
"""Mean absolute difference (0..255, over R, G and B) of two PNG frames of the
same size inside the square of half-side R pixels around (X, Y), and over the
whole frame: how clearly a drag shows where the user grabbed.

    scripts/region_difference.py BEFORE.png AFTER.png X Y R [--min D]

With --min, exits 1 when the region's difference is below D. Reads 8-bit
RGB/RGBA non-interlaced PNGs (what vpm writes) with the standard library.
"""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG")
    pos, idat, width = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace:
                sys.exit(f"{path}: only 8-bit RGB/RGBA non-interlaced PNGs")
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        rows.append(line)
        prev = line
    return width, height, channels, rows


def mean_difference(a, b, x0, y0, x1, y1):
    (_, _, ca, ra), (_, _, cb, rb) = a, b
    total, count = 0, 0
    for y in range(y0, y1):
        for x in range(x0, x1):
            for ch in range(3):
                total += abs(ra[y][x * ca + ch] - rb[y][x * cb + ch])
            count += 3
    return total / max(count, 1)


def main():
    args = sys.argv[1:]
    minimum = None
    if "--min" in args:
        i = args.index("--min")
        minimum = float(args[i + 1])
        del args[i:i + 2]
    if len(args) != 5:
        sys.exit(__doc__)
    a, b = read_png(args[0]), read_png(args[1])
    if a[:2] != b[:2]:
        sys.exit("the frames differ in size")
    w, h = a[:2]
    x, y, r = int(float(args[2])), int(float(args[3])), int(args[4])
    region = mean_difference(a, b, max(0, x - r), max(0, y - r), min(w, x + r), min(h, y + r))
    whole = mean_difference(a, b, 0, 0, w, h)
    print(f"mean |after - before| around the grab ({2 * r}x{2 * r} px at {x},{y}): "
          f"{region:.1f}/255; whole frame {whole:.1f}/255")
    if minimum is not None and region < minimum:
        print(f"below the required {minimum}/255")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
