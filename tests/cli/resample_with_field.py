#!/usr/bin/env python3
"""Resamples a source volume through a displacement field written by
`vpm render --out-displacement F.mha` and compares the result with the
deformed volume `--out-volume` wrote, independently of vpm's warp: for each
voxel x of the source grid, its world point w (the field's Offset,
TransformMatrix and ElementSpacing), the source point w + d(x) back to voxel
indices, a trilinear sample of the source there.

    resample_with_field.py SOURCE.nii[.gz] DEFORMED.nii[.gz] FIELD.mha [--max-mean D]

SOURCE and DEFORMED: NIfTI (int16, int32, float32 or float64, scaled by
scl_slope / scl_inter) on the same grid as the field (what `vpm volume
export` and `--out-volume` write). Prints the mean and the 99th
percentile of |resampled - deformed| and the largest |d| (mm); with
--max-mean exits 1 when the mean exceeds D. Standard library only.
"""
import gzip
import struct
import sys


def read_nifti(path):
    data = open(path, "rb").read()
    if path.endswith(".gz"):
        data = gzip.decompress(data)
    dims = struct.unpack("<8h", data[40:56])
    datatype = struct.unpack("<h", data[70:72])[0]
    offset = int(struct.unpack("<f", data[108:112])[0])
    slope, inter = struct.unpack("<2f", data[112:120])
    formats = {4: ("h", 2), 8: ("i", 4), 16: ("f", 4), 64: ("d", 8)}
    if datatype not in formats:
        sys.exit(f"{path}: NIfTI datatype {datatype} is not int16, int32, float32 or float64")
    code, size = formats[datatype]
    n = dims[1] * dims[2] * dims[3]
    values = struct.unpack(f"<{n}{code}", data[offset:offset + size * n])
    if slope not in (0.0, 1.0) or inter != 0.0:
        values = [v * (slope or 1.0) + inter for v in values]
    return (dims[1], dims[2], dims[3]), values


def read_mha(path):
    data = open(path, "rb").read()
    end = data.index(b"ElementDataFile = LOCAL\n") + len(b"ElementDataFile = LOCAL\n")
    header = {}
    for line in data[:end].decode().splitlines():
        key, value = line.split(" = ")
        header[key] = value
    dims = tuple(int(v) for v in header["DimSize"].split())
    n = dims[0] * dims[1] * dims[2]
    if header["ElementNumberOfChannels"] != "3" or header["ElementType"] != "MET_FLOAT":
        sys.exit(f"{path}: not a 3-channel float field")
    values = struct.unpack(f"<{3 * n}f", data[end:end + 12 * n])
    matrix = [float(v) for v in header["TransformMatrix"].split()]
    axes = [matrix[0:3], matrix[3:6], matrix[6:9]]  # each axis's world direction
    return (dims, values, [float(v) for v in header["Offset"].split()], axes,
            [float(v) for v in header["ElementSpacing"].split()])


def main():
    args = sys.argv[1:]
    max_mean = None
    if "--max-mean" in args:
        i = args.index("--max-mean")
        max_mean = float(args[i + 1])
        del args[i:i + 2]
    (nx, ny, nz), source = read_nifti(args[0])
    dims, deformed = read_nifti(args[1])
    fdims, field, origin, axes, spacing = read_mha(args[2])
    if dims != (nx, ny, nz) or fdims != dims:
        sys.exit(f"grids differ: source {(nx, ny, nz)}, deformed {dims}, field {fdims}")

    def at(i, j, k):
        i, j, k = min(max(i, 0), nx - 1), min(max(j, 0), ny - 1), min(max(k, 0), nz - 1)
        return source[i + nx * (j + ny * k)]

    diffs, largest = [], 0.0
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                v = i + nx * (j + ny * k)
                d = field[3 * v:3 * v + 3]
                largest = max(largest, (d[0] ** 2 + d[1] ** 2 + d[2] ** 2) ** 0.5)
                # w + d - origin, as index: the axes are orthonormal.
                p = [sum(axes[a][c] * spacing[a] * (i, j, k)[a] for a in range(3)) + d[c]
                     for c in range(3)]
                x, y, z = (sum(axes[a][c] * p[c] for c in range(3)) / spacing[a] for a in range(3))
                i0, j0, k0 = int(x // 1), int(y // 1), int(z // 1)
                fx, fy, fz = x - i0, y - j0, z - k0
                value = 0.0
                for di, wi in ((0, 1 - fx), (1, fx)):
                    for dj, wj in ((0, 1 - fy), (1, fy)):
                        for dk, wk in ((0, 1 - fz), (1, fz)):
                            value += wi * wj * wk * at(i0 + di, j0 + dj, k0 + dk)
                diffs.append(abs(value - deformed[v]))
    diffs.sort()
    mean = sum(diffs) / len(diffs)
    print(f"resampled through the field against --out-volume: mean |diff| {mean:.4f}, "
          f"p99 {diffs[int(0.99 * (len(diffs) - 1))]:.4f}; largest |d| {largest:.2f} mm")
    if max_mean is not None and mean > max_mean:
        sys.exit(1)


main()
