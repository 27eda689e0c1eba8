#!/usr/bin/python3
"""vpm against VTK's volume mappers on the same work, in one run.

Two cases, one table set each (--cases): "phantom", the 256^3 abdomen
phantom (--source, exported by `vpm volume export` to NIfTI) with
bench/peer_tf.json; "kidney", the real abdominal CT of
tests/data/ct-abdomen-kidney (122 x 101 x 112 voxels at 3 mm, axis-aligned)
resampled here trilinearly to 1 mm (364 x 301 x 334, int16 Hounsfield units,
written as NIfTI for both) with its own transfer function,
bench/peer_tf_kidney.json. Each case renders its volume with VTK 9.1's
FixedPoint (CPU), GPU (OpenGL on
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

Equal quality: each renderer's still is compared with its own fine-step
reference, the same renderer at --step / --ref-factor (8: 0.125 mm; the
Smart mapper, which renders through the GPU mapper here and takes no step
of its own, is held against the GPU mapper's), and the PSNR is printed beside the
still's time. vpm's stills are also timed at the steps of --vpm-steps
(times --step), coarsest first, down to the first that reaches every
peer's PSNR, and the "equal quality" table compares each peer with vpm at
the coarsest step that reaches its PSNR (coarser than --step where vpm's
PSNR there is above the peer's, finer where below): the goals of issue 29
(2x the fastest VTK mapper, 5x the Smart mapper at its defaults) are
judged there. The peers keep --step (and the Smart mapper its own).
--int16 rounds the volume to int16, as CT scanners store Hounsfield units,
and gives both the same int16 values (vpm holds 2 bytes per voxel, VTK a
vtkShortArray).

Run under a virtual X server (VTK's OpenGL mappers need a context):
    bench/setup_peer.sh      # python3-vtk9, xvfb (apt; bench-only)
    xvfb-run -a -s "-screen 0 1280x1024x24" bench/peer_vtk.py [--build build]
`scripts/bench.sh` (make bench) does so when VTK is installed. On a machine
without VTK (a GPU machine: scripts/gpu-check.sh), `--vpm-only` runs vpm's
side alone, every step of --vpm-steps with its PSNR, and reads the PNGs
with Pillow.
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
except ImportError:  # --vpm-only needs neither
    vtk = numpy_support = None


# --- the volume -------------------------------------------------------------

NIFTI_TYPES = {2: np.uint8, 4: np.int16, 8: np.int32, 16: np.float32, 64: np.float64,
               256: np.int8, 512: np.uint16, 768: np.uint32}


def decode_nifti(raw, path):
    """The bytes of an uncompressed NIfTI-1 file (`path` names it in errors)
    as (its 352-byte header as a bytearray, its voxels as a float32 array
    z, y, x with the scaling applied, pixdim)."""
    header = bytearray(raw[:352])
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
    data = np.frombuffer(raw, dtype=NIFTI_TYPES[datatype], count=nx * ny * nz,
                         offset=vox_offset).astype(np.float32).reshape(nz, ny, nx)
    if slope not in (0.0, 1.0) or inter != 0.0:
        data = data * (slope if slope != 0.0 else 1.0) + inter
    return header, data, pixdim


def read_nifti(path):
    """An uncompressed NIfTI-1 file as (float32 array z, y, x; spacing mm)."""
    with open(path, "rb") as f:
        _, data, pixdim = decode_nifti(f.read(), path)
    return data, tuple(float(s) for s in pixdim[1:4])


def write_int16_nifti(source, path):
    """The float NIfTI-1 `source` rounded to int16 (clipped to its range), as
    a CT scanner stores Hounsfield units: same header, datatype 4. Returns
    the values as an int16 array (z, y, x)."""
    with open(source, "rb") as f:
        raw = f.read()
    header, data, _ = decode_nifti(raw, source)
    extra = raw[352:int(struct.unpack("<f", header[108:112])[0])]
    rounded = np.clip(np.round(data), -32768, 32767).astype("<i2")
    header[70:72] = struct.pack("<h", 4)    # datatype: int16
    header[72:74] = struct.pack("<h", 16)   # bitpix
    header[112:120] = struct.pack("<2f", 1.0, 0.0)  # no scaling
    with open(path, "wb") as f:
        f.write(bytes(header) + extra + rounded.tobytes())
    return rounded


def resample_nifti_gz(source, path, spacing_mm):
    """The gzipped, axis-aligned NIfTI-1 `source` resampled trilinearly to
    `spacing_mm` isotropic, on the same origin and extent (voxel centres
    0, s, 2s, ... mm from the first), rounded to int16 and written
    uncompressed to `path` with a diagonal sform. Returns the int16 array
    (z, y, x)."""
    import gzip
    header, data, pixdim = decode_nifti(gzip.open(source).read(), source)
    srow = [struct.unpack("<4f", header[280 + 16 * r:296 + 16 * r]) for r in range(3)]
    if any(abs(srow[r][c]) > 1e-6 for r in range(3) for c in range(3) if r != c):
        sys.exit(f"peer_vtk: {source}: an oblique volume; this resampling keeps the axes")
    nz, ny, nx = data.shape
    # Separable linear interpolation along each axis: trilinear.
    shape = []
    for axis, n, spacing in ((2, nx, pixdim[1]), (1, ny, pixdim[2]), (0, nz, pixdim[3])):
        m = int(math.floor((n - 1) * spacing / spacing_mm + 1e-6)) + 1
        t = np.arange(m) * (spacing_mm / spacing)
        i0 = np.minimum(np.floor(t).astype(np.int64), n - 2)
        w = (t - i0).astype(np.float32)
        wshape = [1, 1, 1]
        wshape[axis] = m
        w = w.reshape(wshape)
        data = np.take(data, i0, axis=axis) * (1.0 - w) + np.take(data, i0 + 1, axis=axis) * w
        shape.append(m)
    out = np.clip(np.round(data), -32768, 32767).astype("<i2")
    header[40:56] = struct.pack("<8h", 3, shape[0], shape[1], shape[2], 1, 1, 1, 1)
    header[70:72] = struct.pack("<h", 4)    # datatype: int16
    header[72:74] = struct.pack("<h", 16)   # bitpix
    header[76:108] = struct.pack("<8f", pixdim[0], spacing_mm, spacing_mm, spacing_mm, 1, 1, 1, 1)
    header[108:112] = struct.pack("<f", 352.0)
    header[112:120] = struct.pack("<2f", 1.0, 0.0)
    for r in range(3):
        sign = 1.0 if srow[r][r] > 0 else -1.0
        row = [0.0, 0.0, 0.0, srow[r][3]]
        row[r] = sign * spacing_mm
        header[280 + 16 * r:296 + 16 * r] = struct.pack("<4f", *row)
    header[348:352] = bytes(4)  # no extensions
    with open(path, "wb") as f:
        f.write(bytes(header) + out.tobytes())
    return out


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
    if vtk is None:  # --vpm-only: through Pillow, flipped to the same order
        from PIL import Image
        with Image.open(path) as image:
            return np.asarray(image.convert("RGB"))[::-1].copy()
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
STILL_ROWS = {mode: VPM_ROWS[(mode, "still")] for mode in ("mip", "composite")}


def run_vpm(args, case, size, png_dir, with_map, step=None, rows_wanted=None):
    """render_bench's rows (default: all of VPM_ROWS); with_map: through an
    identity backward map (the cost of a deformed volume), else without
    (DeformableScene's undeformed frames); step: every row's step (mm),
    default --step. Returns (camera, MIP window, {row: (wall, CPU / 2)})."""
    wanted = list(rows_wanted or VPM_ROWS.values())
    filt = "|".join(v + "$" for v in wanted)
    cmd = [os.path.join(args.build, "bench", "render_bench"), "--no-reference", "--map-held",
           "--step", str(step or args.step), "--render-tf", case["tf"]]
    cmd += [] if with_map else ["--no-map"]
    cmd += [case["volume"], png_dir, filt, str(size)]
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
            for name in wanted:
                if line.startswith(name + " ") and re.match(r"\s+\d+x\d+", line[len(name):]):
                    fields = line[len(name):].split()
                    rows[name] = (float(fields[3]), float(fields[7]))  # wall, CPU / 2
    if camera is None or window is None or len(rows) != len(wanted):
        sys.exit("peer_vtk: could not read render_bench's output:\n" + out)
    return camera, window, rows


def vpm_png(png_dir, name):
    return read_png(os.path.join(png_dir, name.replace(" ", "_") + ".png"))


def vpm_stills_at(args, case, size, step, tag):
    """vpm's still frames (no map) at `step` mm: {mode: (wall, CPU, RGB)}."""
    png_dir = os.path.join(case["out"], f"vpm_{size}_{tag}")
    os.makedirs(png_dir, exist_ok=True)
    _, _, rows = run_vpm(args, case, size, png_dir, False, step, list(STILL_ROWS.values()))
    return {mode: rows[name] + (vpm_png(png_dir, name),) for mode, name in STILL_ROWS.items()}


def vtk_reference(scene, kind, mode, prop, fine_step):
    """The VTK mapper `kind`'s still at `fine_step` mm (AutoAdjustSampleDistances
    off, full resolution): (wall ms of the one frame, RGB). FixedPoint or GPU:
    the Smart mapper renders through the GPU mapper here and does not take a
    step of its own (its frames at 1 mm and 0.125 mm are the same)."""
    mapper = make_mapper(kind, fine_step)
    set_quality(mapper, kind, False, fine_step)
    if mode == "mip":
        mapper.SetBlendModeToMaximumIntensity()
    else:
        mapper.SetBlendModeToComposite()
    scene.use(mapper, prop)
    scene.window.SetDesiredUpdateRate(0.0001)
    ms, _, rgb = scene.frame()
    return ms, rgb


def prepare_case(args, name):
    """The case's volume (NIfTI both read), transfer function and out folder."""
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(args.out, name)
    os.makedirs(out, exist_ok=True)
    if name == "phantom":
        volume = os.path.join(out, "volume.nii")
        if not os.path.exists(volume):
            subprocess.run([os.path.join(args.build, "client", "vpm"), "volume", "export",
                            args.source, volume], check=True, stdout=subprocess.DEVNULL)
        data, spacing = read_nifti(volume)
        vtk_data = data
        if args.int16:
            volume_int16 = os.path.join(out, "volume_int16.nii")
            vtk_data = write_int16_nifti(volume, volume_int16)
            volume, data = volume_int16, vtk_data.astype(np.float32)
        return {"name": name, "source": args.source, "tf": args.tf, "out": out,
                "volume": volume, "data": data, "image": vtk_image(vtk_data, spacing) if vtk else None,
                "spacing": spacing, "voxels": "int16" if args.int16 else "float32"}
    if name == "kidney":
        source = os.path.join(here, "..", "tests", "data", "ct-abdomen-kidney", "ct_abdomen.nii.gz")
        volume = os.path.join(out, "ct_abdomen_1mm.nii")
        rounded = resample_nifti_gz(source, volume, 1.0)
        _, spacing = read_nifti(volume)
        return {"name": name, "source": "ct_abdomen.nii.gz (3 mm) resampled to 1 mm",
                "tf": args.kidney_tf, "out": out, "volume": volume,
                "data": rounded.astype(np.float32),
                "image": vtk_image(rounded, spacing) if vtk else None,
                "spacing": spacing, "voxels": "int16"}
    sys.exit(f"peer_vtk: unknown case {name}; known: phantom, kidney")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--build", default="build", help="vpm's build folder")
    ap.add_argument("--cases", default="phantom,kidney", help="phantom, kidney or both")
    ap.add_argument("--source", default="phantom:abdomen", help="the phantom case's volume "
                    "(any vpm volume source)")
    ap.add_argument("--tf", default=os.path.join(here, "peer_tf.json"),
                    help="ParaView JSON preset for the phantom case's composite rows")
    ap.add_argument("--kidney-tf", default=os.path.join(here, "peer_tf_kidney.json"),
                    help="ParaView JSON preset for the kidney case's composite rows")
    ap.add_argument("--out", default="out/peer", help="frames and the volumes, one folder a case")
    ap.add_argument("--sizes", default="256,512")
    ap.add_argument("--step", type=float, default=1.0, help="sample step, mm")
    ap.add_argument("--ref-factor", type=float, default=8.0,
                    help="each renderer's reference still: its step / this")
    ap.add_argument("--vpm-steps",
                    default="4,3,2.5,2.25,2,1.75,1.5,1.25,1,0.875,0.75,0.625,0.5,0.45,0.4,0.375,0.35,0.3,0.25",
                    help="vpm's steps (times --step) for the equal-quality table, timed "
                         "coarsest first down to the first whose PSNR reaches every peer's")
    ap.add_argument("--vpm-runs", type=int, default=2,
                    help="processes per vpm step of --vpm-steps (the minimum of each time)")
    ap.add_argument("--int16", action="store_true",
                    help="phantom case: round the volume to int16, as CT scanners store it, for "
                         "both (vpm then holds 2 bytes per voxel, VTK a vtkShortArray)")
    ap.add_argument("--coarse-step", type=float, default=1.5,
                    help="the interactive rows' extra vpm column: full resolution at this "
                         "times --step (vpm's still quality, no map)")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--mappers", default=",".join(MAPPERS))
    ap.add_argument("--modes", default="mip,composite")
    ap.add_argument("--vpm-only", action="store_true",
                    help="vpm's side alone (a machine without VTK, such as a GPU machine): its "
                         "rows, its reference and every step of --vpm-steps, with PSNRs; no "
                         "VTK mapper and no equal-quality table")
    args = ap.parse_args()
    if vtk is None and not args.vpm_only:
        sys.exit("peer_vtk: VTK's Python bindings are missing: run bench/setup_peer.sh "
                 "(Debian's python3-vtk9) and run this with /usr/bin/python3, or pass --vpm-only")
    mappers = [] if args.vpm_only else [m for m in args.mappers.split(",") if m]
    for m in mappers:
        if m not in MAPPERS:
            sys.exit(f"peer_vtk: unknown mapper {m}; known: {', '.join(MAPPERS)}")
    goals = []
    for name in [c for c in args.cases.split(",") if c]:
        goals += run_case(args, prepare_case(args, name), mappers)
    if goals:
        print("\n# Goals at 512^2, equal or better PSNR (CPU ms / cores):")
    for line in goals:
        print("  " + line)
    load = os.getloadavg()
    print(f"# load at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")


class CaseResults:
    """What one case measures, filled size by size."""

    def __init__(self):
        self.results = {}    # (mode, quality, size) -> {renderer: (wall ms, CPU ms, PSNR or None)}
        self.stills = {}     # (renderer, mode, size) -> RGB
        self.refs = {}       # (renderer, mode, size) -> RGB at the reference step
        self.vpm_steps = {}  # (mode, size) -> [(step mm, wall, CPU, PSNR against vpm's reference)]
        self.cross = []      # (mode, size, VTK mapper, PSNR of its still against vpm's)


def measure_vpm(args, case, size, fine_step, r):
    """vpm's rows at `size`, without and through the map, its reference, its
    coarse-step column. Returns render_bench's (camera, MIP window)."""
    png_dir = os.path.join(case["out"], f"vpm_{size}")
    os.makedirs(png_dir, exist_ok=True)
    for renderer, with_map in (("vpm", False), ("vpm map", True)):
        camera, window, rows = run_vpm(args, case, size, png_dir, with_map)
        for (mode, quality), name in VPM_ROWS.items():
            rgb = vpm_png(png_dir, name)
            entry = r.results.setdefault((mode, quality, size), {})
            db = None
            if quality == "still":
                r.stills[(renderer, mode, size)] = rgb
            else:
                db = psnr(rgb, r.stills[(renderer, mode, size)])
            entry[renderer] = (rows[name][0], rows[name][1], db)
    # vpm's reference (the map changes nothing in an undeformed frame's
    # picture: both columns' stills are held against it).
    for mode, (_, _, rgb) in vpm_stills_at(args, case, size, fine_step, "reference").items():
        r.refs[("vpm", mode, size)] = r.refs[("vpm map", mode, size)] = rgb
    for mode in ("mip", "composite"):
        for renderer in ("vpm", "vpm map"):
            wall, cpu, _ = r.results[(mode, "still", size)][renderer]
            db = psnr(r.stills[(renderer, mode, size)], r.refs[(renderer, mode, size)])
            r.results[(mode, "still", size)][renderer] = (wall, cpu, db)
        wall, cpu, db = r.results[(mode, "still", size)]["vpm"]
        r.vpm_steps[(mode, size)] = [(args.step, wall, cpu, db)]
    # Full resolution at a coarser step, in place of half resolution: vpm's
    # still frames at --coarse-step x --step, each with its PSNR against
    # vpm's still at --step, shown in the interactive rows.
    for mode, (wall, cpu, rgb) in vpm_stills_at(args, case, size,
                                                args.coarse_step * args.step, "coarse").items():
        r.results[(mode, "interactive", size)][COARSE] = (
            wall, cpu, psnr(rgb, r.stills[("vpm", mode, size)]))
    return camera, window


def measure_vtk(args, case, size, camera, props, mappers, fine_step, r):
    """Each VTK mapper's still (against its reference) and interactive rows."""
    scene = VtkScene(case["image"], size, camera)
    for kind in mappers:
        for mode in args.modes.split(","):
            ref_kind = "GPU" if kind.startswith("Smart") else kind
            if (ref_kind, mode, size) not in r.refs:
                ms, r.refs[(ref_kind, mode, size)] = vtk_reference(scene, ref_kind, mode,
                                                                   props[mode], fine_step)
                print(f"  reference {ref_kind} {mode} {size}^2 at {fine_step:g} mm: "
                      f"{ms:.0f} ms", flush=True)
            r.refs[(kind, mode, size)] = r.refs[(ref_kind, mode, size)]
            for quality in ("still", "interactive"):
                mapper = make_mapper(kind, args.step)
                if mode == "mip":
                    mapper.SetBlendModeToMaximumIntensity()
                else:
                    mapper.SetBlendModeToComposite()
                set_quality(mapper, kind, quality == "interactive", args.step)
                scene.use(mapper, props[mode])
                rate = 15.0 if quality == "interactive" else 0.0001
                # Interactive: VTK adapts its sample distances to the time
                # of the frames before, so it gets frames to settle.
                ms, cpu, rgb = scene.measure(args.reps, rate, 8 if quality == "interactive" else 1)
                tag = f"vtk_{kind.replace(' ', '').replace('.', '')}_{mode}_{quality}_{size}"
                write_png(os.path.join(case["out"], tag + ".png"), rgb)
                entry = r.results[(mode, quality, size)]
                if quality == "still":
                    r.stills[(kind, mode, size)] = rgb
                    entry[kind] = (ms, cpu, psnr(rgb, r.refs[(kind, mode, size)]))
                else:
                    entry[kind] = (ms, cpu, psnr(rgb, r.stills[(kind, mode, size)]))
        del mapper
    for mode in args.modes.split(","):
        for kind in mappers:
            r.cross.append((mode, size, kind, psnr(r.stills[("vpm", mode, size)],
                                                   r.stills[(kind, mode, size)])))


def time_vpm_steps(args, case, size, mappers, r):
    """vpm's stills at the --vpm-steps in turn, coarsest first, down to the
    first step at which every mode's PSNR reaches the best of the VTK
    mappers' (each against its own reference); --step is timed already."""
    modes = args.modes.split(",")
    # No peer (--vpm-only): no PSNR to reach, so every step is timed.
    target = {mode: max((r.results[(mode, "still", size)][m][2] for m in mappers),
                        default=math.inf) for mode in modes}
    for factor in sorted({float(f) for f in args.vpm_steps.split(",") if f}, reverse=True):
        step = factor * args.step
        if not any(s[0] == step for s in r.vpm_steps[(modes[0], size)]):
            # --vpm-runs processes, the minimum of each: one process's five
            # frames can all fall in a slow spell of a shared machine.
            runs = [vpm_stills_at(args, case, size, step, f"step{step:g}")
                    for _ in range(args.vpm_runs)]
            for mode in modes:
                wall = min(run[mode][0] for run in runs)
                cpu = min(run[mode][1] for run in runs)
                rgb = runs[0][mode][2]
                r.vpm_steps[(mode, size)].append(
                    (step, wall, cpu, psnr(rgb, r.refs[("vpm", mode, size)])))
        if all(s[3] >= target[mode] for mode in modes for s in r.vpm_steps[(mode, size)]
               if s[0] == step):
            break


def run_case(args, case, mappers):
    """One case's tables; returns its goal lines (512^2 stills)."""
    data = case["data"]
    spacing = case["spacing"]
    value_range = (float(data.min()), float(data.max()))
    preset = read_paraview_preset(case["tf"])
    fine_step = args.step / args.ref_factor
    load = os.getloadavg()
    print(f"\n## case {case['name']}: {case['source']}, {data.shape[2]}x{data.shape[1]}x{data.shape[0]}, "
          f"spacing {spacing[0]:.4f} {spacing[1]:.4f} {spacing[2]:.4f} mm, step {args.step} mm "
          f"(references {fine_step:g} mm), {case['voxels']} voxels, composite: {case['tf']}; "
          f"VTK {vtk.vtkVersion.GetVTKVersion() if vtk else 'not loaded'}; {os.cpu_count()} cores; "
          f"load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)
    r = CaseResults()
    for size in [int(s) for s in args.sizes.split(",")]:
        camera, window = measure_vpm(args, case, size, fine_step, r)
        if mappers:
            props = {"mip": mip_property(window["width"], window["level"], value_range),
                     "composite": composite_property(preset, True)}
            measure_vtk(args, case, size, camera, props, mappers, fine_step, r)
        time_vpm_steps(args, case, size, mappers, r)
    results, vpm_steps, cross = r.results, r.vpm_steps, r.cross

    print(f"\n### case {case['name']}: wall ms per frame (min of {args.reps}), image read back:")
    print_table(results, mappers, 0)
    print(f"\n### case {case['name']}: process CPU ms per frame / {CORES} cores (min of "
          f"{args.reps}): what the frame costs the machine, less disturbed by other load:")
    print_table(results, mappers, 1)
    goals = []
    if mappers:
        print(f"\n### case {case['name']}: stills at equal or better PSNR, each against its "
              f"own reference at {fine_step:g} mm:")
        goals = print_equal_quality(case["name"], results, vpm_steps, mappers)
    print(f"\n### case {case['name']}: vpm's stills at each step timed, CPU ms / {CORES} cores "
          f"(PSNR against vpm's reference):")
    print_vpm_steps(args, vpm_steps)
    if cross:
        print(f"\nPSNR of each VTK still against vpm's (same camera, step, window or transfer "
              f"function; the frames are in {case['out']}):")
    for mode, size, kind, db in cross:
        print(f"  still {mode} {size}^2, VTK {kind}: {db:.1f} dB")
    load = os.getloadavg()
    print(f"# case {case['name']}: load at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}",
          flush=True)
    return goals


def print_vpm_steps(args, vpm_steps):
    """vpm's stills at every step timed, per size, coarsest first: CPU ms
    (PSNR against vpm's reference) per mode."""
    modes = args.modes.split(",")
    print("| size | step mm | " + " | ".join(modes) + " |")
    print("|" + "---|" * (2 + len(modes)))
    for size in [int(s) for s in args.sizes.split(",")]:
        for step in sorted({s[0] for s in vpm_steps[(modes[0], size)]}, reverse=True):
            cells = [next(f"{c:.1f} ({db:.1f} dB)" for st, _, c, db in vpm_steps[(m, size)]
                          if st == step) for m in modes]
            print(f"| {size}^2 | {step:g} | " + " | ".join(cells) + " |")


def print_equal_quality(case_name, results, vpm_steps, mappers):
    """Per still and peer (the fastest VTK mapper at the same step, by CPU
    time, and Smart at its defaults): vpm at the coarsest step whose PSNR
    reaches the peer's, and the ratios. Returns the 512^2 goal lines."""
    head = ["still", "size", "peer", "peer CPU ms (dB)", "peer wall ms", "vpm step mm",
            "vpm CPU ms (dB)", "vpm wall ms", "peer / vpm CPU", "peer / vpm wall", "goal"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    goals = []
    for (mode, quality, size), entry in sorted(results.items(), key=lambda kv: (kv[0][0] != "mip", kv[0][2])):
        if quality != "still":
            continue
        same_step = [m for m in mappers if m != "Smart defaults"]
        peers = []
        if same_step:
            peers.append((min(same_step, key=lambda m: entry[m][1]), 2.0))
        if "Smart defaults" in mappers:
            peers.append(("Smart defaults", 5.0))
        for peer, goal in peers:
            p_wall, p_cpu, p_db = entry[peer]
            timed = sorted(vpm_steps[(mode, size)], reverse=True)  # coarsest first
            reached = [s for s in timed if s[3] >= p_db]
            step, v_wall, v_cpu, v_db = reached[0] if reached else timed[-1]
            ratio_cpu, ratio_wall = p_cpu / v_cpu, p_wall / v_wall
            label = f"{'MIP' if mode == 'mip' else 'composite'}"
            met = "met" if reached and ratio_cpu >= goal else "not met"
            if not reached:
                met += f" (vpm's PSNR stays under the peer's down to {step:g} mm)"
            row = [label, f"{size}^2", f"VTK {peer}", f"{p_cpu:.1f} ({p_db:.1f} dB)",
                   f"{p_wall:.1f}", f"{step:g}", f"{v_cpu:.1f} ({v_db:.1f} dB)", f"{v_wall:.1f}",
                   f"{ratio_cpu:.2f}", f"{ratio_wall:.2f}", f"{goal:g}x: {met}"]
            print("| " + " | ".join(row) + " |")
            if size == 512:
                goals.append(f"{case_name} still {label} 512^2 against VTK {peer}: "
                             f"{ratio_cpu:.2f}x in CPU time, {ratio_wall:.2f}x wall, vpm at "
                             f"{step:g} mm {v_db:.1f} dB against {p_db:.1f} dB; goal {goal:g}x "
                             f"{met}")
    return goals


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
    print("(still: ms (PSNR against the same renderer's reference at step / --ref-factor, dB); "
          "interactive: ms (PSNR against the same renderer's still frame, dB); fastest VTK: "
          "of FixedPoint, GPU and Smart at the same step; vpm full resolution, coarse step: "
          "vpm's still quality at --coarse-step x the step, no map, against vpm's still)")


if __name__ == "__main__":
    main()
