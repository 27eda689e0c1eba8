#!/usr/bin/python3
"""vpm against VTK's volume mappers on the same work, in one run.

Renders one volume (default: the 256^3 abdomen phantom, exported by
`vpm volume export` to NIfTI) with VTK 9.1's FixedPoint (CPU), GPU (OpenGL on
llvmpipe) and Smart mappers, and with vpm's `render_bench`, with the same
camera (read from render_bench's "camera:" line), frame size, sample step
(1 mm), MIP window and transfer function (a ParaView JSON preset, read by
both: `render_bench --render-tf`, and here into vtkColorTransferFunction /
vtkPiecewiseFunction), then prints one table: ms per frame and ratios for
MIP and composite at 256^2 and 512^2, still and interactive.

Still: VTK with AutoAdjustSampleDistances off, SampleDistance 1 mm,
ImageSampleDistance 1; vpm's still quality at --step 1. Interactive: VTK's
level of detail at DesiredUpdateRate 15 (the rate vtkRenderWindowInteractor
asks for while the mouse moves; AutoAdjustSampleDistances on, as VTK
defaults it), against vpm's interactive quality (half resolution, upscaled)
and, in a column of its own, vpm's still quality at full resolution and a
coarser step (--coarse-step x --step, 1.5 mm by default: what VTK's LOD does
where its frame budget allows); each with its PSNR against its own still
frame (vpm's at --step). "VTK Smart defaults": the
Smart mapper as ParaView and Slicer users get it, VTK choosing its own
step from the spacing. vpm renders without the map (what DeformableScene
does while nothing is deformed) and, in its own column, through an
identity map (what a deformed volume costs). Times: wall ms per frame, the
minimum over --reps, with the image read back (vpm's `wall`; VTK: Render()
and glReadPixels), and process CPU ms per frame / cores, less disturbed by
other load. Camera and geometry: the PSNR of each VTK still against vpm's
is printed, and the PNGs of all are written to --out for looking at.
--int16 rounds the volume to int16, as CT scanners store Hounsfield units,
and gives both the same int16 values (vpm holds 2 bytes per voxel, VTK a
vtkShortArray).

Run under a virtual X server (VTK's OpenGL mappers need a context):
    bench/setup_peer.sh      # python3-vtk9, xvfb (apt; bench-only)
    xvfb-run -a -s "-screen 0 1280x1024x24" bench/peer_vtk.py [--build build]
`scripts/bench.sh` (make bench) does so when VTK is installed.
"""
import argparse
import json
import math
import os
import re
import struct
import subprocess
import sys
import time

import numpy as np

try:
    import vtk
    from vtk.util import numpy_support
except ImportError:
    sys.exit("peer_vtk: VTK's Python bindings are missing: run bench/setup_peer.sh "
             "(Debian's python3-vtk9) and run this with /usr/bin/python3")


# --- the volume -------------------------------------------------------------

NIFTI_TYPES = {2: np.uint8, 4: np.int16, 8: np.int32, 16: np.float32, 64: np.float64,
               256: np.int8, 512: np.uint16, 768: np.uint32}


def read_nifti(path):
    """An uncompressed NIfTI-1 file as (float32 array z, y, x; spacing mm)."""
    with open(path, "rb") as f:
        header = f.read(352)
        if len(header) < 352 or struct.unpack("<i", header[:4])[0] != 348:
            sys.exit(f"peer_vtk: {path}: not a little-endian NIfTI-1 file")
        dim = struct.unpack("<8h", header[40:56])
        datatype = struct.unpack("<h", header[70:72])[0]
        pixdim = struct.unpack("<8f", header[76:108])
        vox_offset = int(struct.unpack("<f", header[108:112])[0])
        slope, inter = struct.unpack("<2f", header[112:120])
        if datatype not in NIFTI_TYPES or dim[0] < 3 or (dim[0] > 3 and any(d > 1 for d in dim[4:dim[0] + 1])):
            sys.exit(f"peer_vtk: {path}: a 3D volume of a plain type is needed")
        nx, ny, nz = dim[1:4]
        f.seek(vox_offset)
        data = np.fromfile(f, dtype=NIFTI_TYPES[datatype], count=nx * ny * nz)
    data = data.astype(np.float32).reshape(nz, ny, nx)
    if slope not in (0.0, 1.0) or inter != 0.0:
        data = data * (slope if slope != 0.0 else 1.0) + inter
    return data, tuple(float(s) for s in pixdim[1:4])


def write_int16_nifti(source, path):
    """The float NIfTI-1 `source` rounded to int16 (clipped to its range), as
    a CT scanner stores Hounsfield units: same header, datatype 4. Returns
    the values as an int16 array (z, y, x)."""
    with open(source, "rb") as f:
        header = bytearray(f.read(352))
        vox_offset = int(struct.unpack("<f", header[108:112])[0])
        f.seek(0)
        extra = f.read(vox_offset)[352:]
    data, _ = read_nifti(source)
    rounded = np.clip(np.round(data), -32768, 32767).astype("<i2")
    header[70:72] = struct.pack("<h", 4)    # datatype: int16
    header[72:74] = struct.pack("<h", 16)   # bitpix
    header[112:120] = struct.pack("<2f", 1.0, 0.0)  # no scaling
    with open(path, "wb") as f:
        f.write(bytes(header) + extra + rounded.tobytes())
    return rounded


def vtk_image(data, spacing):
    """vtkImageData in vpm's physical voxel space: voxel (i, j, k) at
    (i, j, k) * spacing mm, origin 0 (docs/ALGORITHM.md section 0); float32
    or int16 values as given."""
    nz, ny, nx = data.shape
    image = vtk.vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    image.SetOrigin(0.0, 0.0, 0.0)
    array_type = vtk.VTK_SHORT if data.dtype == np.int16 else vtk.VTK_FLOAT
    scalars = numpy_support.numpy_to_vtk(data.ravel(), deep=True, array_type=array_type)
    scalars.SetName("values")
    image.GetPointData().SetScalars(scalars)
    return image


# --- transfer functions -----------------------------------------------------

def read_paraview_preset(path):
    name = None
    if "#" in path:
        path, name = path.split("#", 1)
    with open(path) as f:
        presets = json.load(f)
    if isinstance(presets, dict):
        presets = [presets]
    for p in presets:
        if name is None or p.get("Name") == name:
            return p
    sys.exit(f"peer_vtk: {path}: no preset named {name}")


def composite_property(preset, shading):
    """The preset as VTK's colour and opacity functions: opacity per unit
    distance (ScalarOpacityUnitDistance 1 mm), as vpm reads it."""
    colour = vtk.vtkColorTransferFunction()
    colour.SetColorSpaceToRGB()
    rgb = preset["RGBPoints"]
    for i in range(0, len(rgb), 4):
        colour.AddRGBPoint(*rgb[i:i + 4])
    opacity = vtk.vtkPiecewiseFunction()
    points = preset.get("Points")
    if points:
        for i in range(0, len(points), 4):
            opacity.AddPoint(*points[i:i + 4])
    else:
        opacity.AddPoint(rgb[0], 0.0)
        opacity.AddPoint(rgb[-4], 1.0)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(1.0)
    prop.SetInterpolationTypeToLinear()
    # vpm's lighting for presets that carry none (RaycastSettings): a
    # headlight, ambient 0.35, diffuse 0.65, specular 0.25, shininess 24.
    prop.SetShade(1 if shading else 0)
    prop.SetAmbient(0.35)
    prop.SetDiffuse(0.65)
    prop.SetSpecular(0.25)
    prop.SetSpecularPower(24.0)
    return prop


def mip_property(width, level, value_range):
    """Grey from black at level - width/2 to white at level + width/2, opaque:
    vpm's MIP window."""
    colour = vtk.vtkColorTransferFunction()
    colour.AddRGBPoint(level - 0.5 * width, 0.0, 0.0, 0.0)
    colour.AddRGBPoint(level + 0.5 * width, 1.0, 1.0, 1.0)
    opacity = vtk.vtkPiecewiseFunction()
    opacity.AddPoint(min(value_range[0], level - 0.5 * width), 1.0)
    opacity.AddPoint(max(value_range[1], level + 0.5 * width), 1.0)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    return prop


# --- VTK rendering ----------------------------------------------------------

# "Smart 1 mm": the Smart mapper at the same step; "Smart defaults": as
# ParaView and Slicer users get it, VTK choosing its own step from the
# spacing (finer than 1 mm for stills).
MAPPERS = ["FixedPoint", "GPU", "Smart 1 mm", "Smart defaults"]
CORES = os.cpu_count() or 2


def make_mapper(kind, step_mm):
    if kind == "FixedPoint":
        m = vtk.vtkFixedPointVolumeRayCastMapper()
        m.SetNumberOfThreads(os.cpu_count() or 2)
    elif kind == "GPU":
        m = vtk.vtkOpenGLGPUVolumeRayCastMapper()
        m.SetUseJittering(0)
    else:
        m = vtk.vtkSmartVolumeMapper()
        m.SetRequestedRenderModeToDefault()
        if kind == "Smart defaults":
            return m
    m.SetSampleDistance(step_mm)
    return m


def set_quality(mapper, kind, interactive, step_mm):
    """Still: fixed 1 mm (or the Smart row's step), full resolution.
    Interactive: VTK's own level of detail (AutoAdjustSampleDistances)."""
    if kind.startswith("Smart"):
        # The Smart mapper switches itself by the window's DesiredUpdateRate
        # against its InteractiveUpdateRate (1): above, auto-adjusted
        # (InteractiveAdjustSampleDistances, on by default); below, its
        # AutoAdjustSampleDistances (on by default: VTK's own step).
        if kind == "Smart 1 mm":
            mapper.SetAutoAdjustSampleDistances(0)
        return
    mapper.SetAutoAdjustSampleDistances(1 if interactive else 0)
    if not interactive:
        mapper.SetSampleDistance(step_mm)
        mapper.SetImageSampleDistance(1.0)


class VtkScene:
    def __init__(self, image, size, camera):
        self.window = vtk.vtkRenderWindow()
        self.window.SetOffScreenRendering(1)
        self.window.SetSize(size, size)
        self.window.SetMultiSamples(0)
        self.renderer = vtk.vtkRenderer()
        self.renderer.SetBackground(0.0, 0.0, 0.0)
        self.window.AddRenderer(self.renderer)
        self.volume = vtk.vtkVolume()
        self.renderer.AddVolume(self.volume)
        self.image = image
        self.size = size
        cam = self.renderer.GetActiveCamera()
        cam.SetPosition(*camera["eye"])
        cam.SetFocalPoint(*camera["target"])
        cam.SetViewUp(*camera["up"])
        cam.SetViewAngle(camera["fov"])
        self.grab = vtk.vtkWindowToImageFilter()
        self.grab.SetInput(self.window)
        self.grab.SetInputBufferTypeToRGB()
        self.grab.ReadFrontBufferOff()
        self.grab.ShouldRerenderOff()

    def use(self, mapper, prop):
        mapper.SetInputData(self.image)
        self.volume.SetMapper(mapper)
        self.volume.SetProperty(prop)
        self.renderer.ResetCameraClippingRange()

    def frame(self):
        """Renders and reads back; returns (wall ms, process CPU ms / cores,
        RGB array rows bottom-up)."""
        c0, t0 = time.process_time(), time.perf_counter()
        self.window.Render()
        self.grab.Modified()
        self.grab.Update()
        ms = (time.perf_counter() - t0) * 1e3
        cpu = (time.process_time() - c0) * 1e3 / CORES
        out = self.grab.GetOutput()
        rgb = numpy_support.vtk_to_numpy(out.GetPointData().GetScalars())
        return ms, cpu, rgb.reshape(self.size, self.size, -1)[:, :, :3].copy()

    def measure(self, reps, update_rate, warmup):
        """(min wall ms, min CPU ms / cores, last frame)."""
        self.window.SetDesiredUpdateRate(update_rate)
        for _ in range(warmup):
            self.frame()
        best, best_cpu, rgb = math.inf, math.inf, None
        for _ in range(reps):
            ms, cpu, rgb = self.frame()
            best, best_cpu = min(best, ms), min(best_cpu, cpu)
        return best, best_cpu, rgb


# --- images -----------------------------------------------------------------

def psnr(a, b):
    d = a.astype(np.float64) - b.astype(np.float64)
    mse = float(np.mean(d * d))
    return 99.0 if mse == 0.0 else 10.0 * math.log10(255.0 * 255.0 / mse)


def read_png(path):
    """RGB rows bottom-up (VTK's order), as VtkScene.frame returns them."""
    reader = vtk.vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    out = reader.GetOutput()
    w, h, _ = out.GetDimensions()
    a = numpy_support.vtk_to_numpy(out.GetPointData().GetScalars())
    return a.reshape(h, w, -1)[:, :, :3].copy()


def write_png(path, rgb):
    h, w, _ = rgb.shape
    image = vtk.vtkImageData()
    image.SetDimensions(w, h, 1)
    image.GetPointData().SetScalars(
        numpy_support.numpy_to_vtk(rgb.reshape(-1, 3), deep=True, array_type=vtk.VTK_UNSIGNED_CHAR))
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(path)
    writer.SetInputData(image)
    writer.Write()


# --- vpm --------------------------------------------------------------------

COARSE = "vpm coarse"  # the results' key for vpm at full resolution, coarse step
VPM_ROWS = {("mip", "still"): "still MIP", ("mip", "interactive"): "interactive MIP",
            ("composite", "still"): "still DVR custom",
            ("composite", "interactive"): "interactive DVR custom"}


def run_vpm(args, volume_path, size, png_dir, with_map, step=None):
    """render_bench's rows; with_map: through an identity backward map (the
    cost of a deformed volume), else without (DeformableScene's undeformed
    frames); step: every row's step (mm), default --step."""
    filt = "|".join(v + "$" for v in VPM_ROWS.values())
    cmd = [os.path.join(args.build, "bench", "render_bench"), "--no-reference", "--map-held",
           "--step", str(step or args.step), "--render-tf", args.tf]
    cmd += [] if with_map else ["--no-map"]
    cmd += [volume_path, png_dir, filt, str(size)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    camera, window, rows = None, None, {}
    for line in out.splitlines():
        if line.startswith("camera:"):
            n = [float(x) for x in re.findall(r"-?\d+\.\d+", line)]
            camera = {"eye": n[0:3], "target": n[3:6], "up": n[6:9], "fov": n[9]}
        elif line.startswith("mip window:"):
            n = [float(x) for x in re.findall(r"-?\d+\.\d+", line)]
            window = {"width": n[0], "level": n[1]}
        else:
            for name in VPM_ROWS.values():
                if line.startswith(name + " ") and re.match(r"\s+\d+x\d+", line[len(name):]):
                    fields = line[len(name):].split()
                    rows[name] = (float(fields[3]), float(fields[7]))  # wall, CPU / 2
    if camera is None or window is None or len(rows) != len(VPM_ROWS):
        sys.exit("peer_vtk: could not read render_bench's output:\n" + out)
    return camera, window, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--build", default="build", help="vpm's build folder")
    ap.add_argument("--source", default="phantom:abdomen", help="any vpm volume source")
    ap.add_argument("--tf", default=os.path.join(here, "peer_tf.json"),
                    help="ParaView JSON preset for the composite rows")
    ap.add_argument("--out", default="out/peer", help="frames and the exported volume")
    ap.add_argument("--sizes", default="256,512")
    ap.add_argument("--step", type=float, default=1.0, help="sample step, mm")
    ap.add_argument("--int16", action="store_true",
                    help="round the volume to int16, as CT scanners store it, for both "
                         "(vpm then holds 2 bytes per voxel, VTK a vtkShortArray)")
    ap.add_argument("--coarse-step", type=float, default=1.5,
                    help="the interactive rows' extra vpm column: full resolution at this "
                         "times --step (vpm's still quality, no map)")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--mappers", default=",".join(MAPPERS))
    ap.add_argument("--modes", default="mip,composite")
    args = ap.parse_args()
    mappers = [m for m in args.mappers.split(",") if m]
    for m in mappers:
        if m not in MAPPERS:
            sys.exit(f"peer_vtk: unknown mapper {m}; known: {', '.join(MAPPERS)}")
    os.makedirs(args.out, exist_ok=True)
    volume_path = os.path.join(args.out, "volume.nii")
    if not os.path.exists(volume_path):
        subprocess.run([os.path.join(args.build, "client", "vpm"), "volume", "export",
                        args.source, volume_path], check=True, stdout=subprocess.DEVNULL)
    data, spacing = read_nifti(volume_path)
    image = vtk_image(data, spacing)
    if args.int16:
        int16_path = os.path.join(args.out, "volume_int16.nii")
        rounded = write_int16_nifti(volume_path, int16_path)
        volume_path = int16_path
        data = rounded.astype(np.float32)
        image = vtk_image(rounded, spacing)
    value_range = (float(data.min()), float(data.max()))
    preset = read_paraview_preset(args.tf)
    load = os.getloadavg()
    print(f"# peer benchmark: {args.source} {data.shape[2]}x{data.shape[1]}x{data.shape[0]}, "
          f"spacing {spacing[0]:.4f} {spacing[1]:.4f} {spacing[2]:.4f} mm, step {args.step} mm, "
          f"{'int16' if args.int16 else 'float32'} voxels, composite: {args.tf}; VTK {vtk.vtkVersion.GetVTKVersion()}; "
          f"{os.cpu_count()} cores; load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")

    results = {}  # (mode, quality, size) -> {renderer: (ms, psnr or None)}
    stills = {}   # (renderer, mode, size) -> RGB
    cross = []
    for size in [int(s) for s in args.sizes.split(",")]:
        png_dir = os.path.join(args.out, f"vpm_{size}")
        os.makedirs(png_dir, exist_ok=True)
        for renderer, with_map in (("vpm", False), ("vpm map", True)):
            camera, window, rows = run_vpm(args, volume_path, size, png_dir, with_map)
            for (mode, quality), name in VPM_ROWS.items():
                rgb = read_png(os.path.join(png_dir, name.replace(" ", "_") + ".png"))
                entry = results.setdefault((mode, quality, size), {})
                db = None
                if quality == "still":
                    stills[(renderer, mode, size)] = rgb
                else:
                    db = psnr(rgb, stills[(renderer, mode, size)])
                entry[renderer] = (rows[name][0], rows[name][1], db)
        # Full resolution at a coarser step, in place of half resolution:
        # vpm's still frames at --coarse-step x --step, each with its PSNR
        # against vpm's still at --step, shown in the interactive rows.
        coarse_dir = os.path.join(args.out, f"vpm_{size}_coarse")
        os.makedirs(coarse_dir, exist_ok=True)
        _, _, rows = run_vpm(args, volume_path, size, coarse_dir, False,
                             args.coarse_step * args.step)
        for mode in ("mip", "composite"):
            name = VPM_ROWS[(mode, "still")]
            rgb = read_png(os.path.join(coarse_dir, name.replace(" ", "_") + ".png"))
            results[(mode, "interactive", size)][COARSE] = (
                rows[name][0], rows[name][1], psnr(rgb, stills[("vpm", mode, size)]))
        scene = VtkScene(image, size, camera)
        props = {"mip": mip_property(window["width"], window["level"], value_range),
                 "composite": composite_property(preset, True)}
        for kind in mappers:
            for mode in args.modes.split(","):
                for quality in ("still", "interactive"):
                    mapper = make_mapper(kind, args.step)
                    if mode == "mip":
                        mapper.SetBlendModeToMaximumIntensity()
                    else:
                        mapper.SetBlendModeToComposite()
                    set_quality(mapper, kind, quality == "interactive", args.step)
                    scene.use(mapper, props[mode])
                    rate = 15.0 if quality == "interactive" else 0.0001
                    # Interactive: VTK adapts its sample distances to the
                    # time of the frames before, so it gets frames to settle.
                    ms, cpu, rgb = scene.measure(args.reps, rate,
                                                 8 if quality == "interactive" else 1)
                    tag = f"vtk_{kind.replace(' ', '').replace('.', '')}_{mode}_{quality}_{size}"
                    write_png(os.path.join(args.out, tag + ".png"), rgb)
                    entry = results[(mode, quality, size)]
                    if quality == "still":
                        stills[(kind, mode, size)] = rgb
                        entry[kind] = (ms, cpu, None)
                    else:
                        entry[kind] = (ms, cpu, psnr(rgb, stills[(kind, mode, size)]))
            del mapper
        for mode in args.modes.split(","):
            for kind in mappers:
                cross.append((mode, size, kind, psnr(stills[("vpm", mode, size)],
                                                     stills[(kind, mode, size)])))

    print("\nWall ms per frame (min of %d), image read back:" % args.reps)
    print_table(results, mappers, 0)
    print("\nProcess CPU ms per frame / %d cores (min of %d): what the frame costs the "
          "machine, less disturbed by other load:" % (CORES, args.reps))
    print_table(results, mappers, 1)
    print(f"\nPSNR of each VTK still against vpm's (same camera, step, window or transfer "
          f"function; the frames are in {args.out}):")
    for mode, size, kind, db in cross:
        print(f"  still {mode} {size}^2, VTK {kind}: {db:.1f} dB")
    load = os.getloadavg()
    print(f"# load at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")


def print_table(results, mappers, column):
    """One row per frame kind; column 0: wall ms, 1: CPU ms / cores."""
    renderers = ["vpm", "vpm map", COARSE] + mappers
    names = {"vpm": "vpm", "vpm map": "vpm through a map",
             COARSE: "vpm full resolution, coarse step"}
    head = ["frame", "size"] + [f"{names.get(r, 'VTK ' + r)} ms" for r in renderers]
    head += ["fastest VTK / vpm"]
    smart = [m for m in mappers if m == "Smart defaults"]
    head += [f"{m} / vpm" for m in smart]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    order = lambda kv: (kv[0][1] != "still", kv[0][0] != "mip", kv[0][2])
    for (mode, quality, size), entry in sorted(results.items(), key=order):
        def cell(r):
            if r not in entry:
                return "-"
            ms, db = entry[r][column], entry[r][2]
            return f"{ms:.1f}" if db is None else f"{ms:.1f} ({db:.1f} dB)"
        vpm_ms = entry["vpm"][column]
        same_step = [entry[m][column] for m in mappers if m in entry and m != "Smart defaults"]
        row = [f"{quality} {'MIP' if mode == 'mip' else 'composite'}", f"{size}^2"]
        row += [cell(r) for r in renderers]
        row.append(f"{min(same_step) / vpm_ms:.2f}" if same_step else "-")
        row += [f"{entry[m][column] / vpm_ms:.2f}" if m in entry else "-" for m in smart]
        print("| " + " | ".join(row) + " |")
    print("(interactive: ms (PSNR against the same renderer's still frame, dB); fastest VTK: "
          "of FixedPoint, GPU and Smart at the same step; vpm full resolution, coarse step: "
          "vpm's still quality at --coarse-step x the step, no map, against vpm's still)")


if __name__ == "__main__":
    main()
