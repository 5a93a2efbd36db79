"""Small measured-surface files built byte by byte for the reading tests.

Each writer takes heights ``z`` (nx, ny) in micrometres, ``z[i, j]`` at the i-th x and
j-th y (both ascending), the spacings dx, dy in micrometres, and writes the file as the
format's specification lays it out (not through the reader under test):

- x3p (ISO 25178-72 / ISO 5436-2): a zip of ``main.xml`` and ``bindata/data.bin``, the
  points little-endian with x running fastest, lengths in metres;
- sdf (ISO 25178-71, binary): the ``bISO-1.0`` header, then the profiles (one per y) of
  int16 counts times Zscale [m]; -32768 marks a missing point;
- sur (Digital Surf): the 512-byte header, then int16 counts (y rows of x), heights =
  counts x the z scale, in the header's unit (here \u00b5m, written as b"\\xe6m");
- plu (Sensofar): the header, calibration and configuration blocks, then float32 heights
  [\u00b5m] in y rows of x; 1000001 marks a missing point;
- opd (Wyko): a 2-byte prelude, a directory of 24-byte block entries, then the blocks: the
  raster (x index first, y stored top-down, float32 in wavelengths / Mult), the wavelength
  [nm], Mult and the pixel size [mm];
- x y z text and netCDF ``heights``: the project's own formats (docs/scene-file.md).

Imported by the tests as ``from surface_files import ...``.
"""
import struct
import zipfile

import numpy as np

__all__ = ["write_x3p", "write_sdf", "write_sur", "write_plu", "write_opd", "write_xyz",
           "write_netcdf_heights", "WRITERS", "QUANTUM_UM"]

#: The smallest height step [um] each writer can store (int16 formats store counts).
QUANTUM_UM = {"x3p": 0.0, "sdf": 1e-3, "sur": 1e-3, "plu": 0.0, "opd": 0.0, "xyz": 0.0,
              "nc": 0.0}


def write_x3p(path, z, dx, dy):
    nx, ny = z.shape
    xml = f"""<?xml version="1.0" encoding="UTF-8"?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
  <Record1>
    <Revision>ISO5436 - 2000</Revision>
    <FeatureType>SUR</FeatureType>
    <Axes>
      <CX><AxisType>I</AxisType><DataType>D</DataType>
          <Increment>{dx * 1e-6:.17g}</Increment><Offset>0</Offset></CX>
      <CY><AxisType>I</AxisType><DataType>D</DataType>
          <Increment>{dy * 1e-6:.17g}</Increment><Offset>0</Offset></CY>
      <CZ><AxisType>A</AxisType><DataType>D</DataType></CZ>
    </Axes>
  </Record1>
  <Record3>
    <MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ></MatrixDimension>
    <DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>
  </Record3>
</p:ISO5436_2>
"""
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("main.xml", xml)
        zf.writestr("bindata/data.bin", (z.T * 1e-6).astype("<f8").tobytes())


def write_sdf(path, z, dx, dy, missing=None):
    nx, ny = z.shape
    zscale = 1e-9                                     # m per count: 1 nm
    counts = np.rint(z * 1e-6 / zscale).astype("<i2")
    if missing is not None:
        counts[missing] = -32768
    head = struct.pack("<8s10s12s12sHHddddBBB", b"bISO-1.0", b"test", b"010120260000",
                       b"010120260000", nx, ny, dx * 1e-6, dy * 1e-6, zscale, zscale, 0, 5, 0)
    with open(path, "wb") as f:
        f.write(head + counts.T.tobytes())


def write_sur(path, z, dx, dy):
    nx, ny = z.shape
    scale = 1e-3                                      # um per count
    counts = np.rint(z / scale).astype("<i2")
    um = b"\xe6m"
    head = struct.pack(
        "<12sHHHH30s30sHHHHHIIHiiiiIfff16s16s16s16s16s16s16s16s16sfffHHHIIIHHHHHHHfIIHHH128s"
        "fff34s",
        b"DIGITAL SURF", 0, 1, 1, 2, b"test", b"test", 0, 0, 0, 0, 1, 0, 0, 16,
        int(counts.min()), int(counts.max()), nx, ny, nx * ny, dx, dy, scale,
        b"X", b"Y", b"Z", um, um, um, um, um, um, 1.0, 1.0, 1.0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 1, 1, 2026, 0, 0.0, 0, 0, 0, 0, 0, b"", 0.0, 0.0, 0.0, b"")
    assert len(head) == 512
    with open(path, "wb") as f:
        f.write(head + counts.T.tobytes())


def write_plu(path, z, dx, dy, missing=None):
    nx, ny = z.shape
    data = np.array(z, dtype="<f4")
    if missing is not None:
        data[missing] = 1000001.0
    head = struct.pack("<128sI256s", b"01/01/2026 00:00:00", 0, b"test")
    calib = struct.pack("<IIIfffffff", ny, nx, nx * ny, 1.0, dx, dy, 0, 0, 1.0, 0)
    conf1 = struct.pack("<IIIII", 3, 0, 0, 0, 0)
    scan = struct.pack("<IIIIIdfII", nx, ny, nx, ny, 0, 0.0, 0.0, 0, 0)
    conf2 = struct.pack("<BBBB", 0, 1, 0, 0) + struct.pack("<B3sI", 0, b"", 0)
    layer = struct.pack("<II", ny, nx) + data.T.tobytes() + \
        struct.pack("<ff", float(np.min(z)), float(np.max(z)))
    with open(path, "wb") as f:
        f.write(head + calib + conf1 + scan + conf2 + layer)


def _opd_entry(name, kind, length):
    return struct.pack("<16shlH", name.encode(), kind, length, 0)


def write_opd(path, z, dx, dy):
    nx, ny = z.shape
    wavelength, mult = 632.8, 1                       # nm; heights in wavelengths / Mult
    raster = np.array(z * 1e3 / wavelength * mult, dtype="<f4")[:, ::-1]   # y top-down
    blocks = [("RAW DATA", 3, struct.pack("<HHH", nx, ny, 4) + raster.tobytes()),
              ("Wavelength", 7, struct.pack("<f", wavelength)),
              ("Mult", 6, struct.pack("<h", mult)),
              ("Pixel_size", 7, struct.pack("<f", dx * 1e-3)),
              ("Aspect", 7, struct.pack("<f", dy / dx))]
    directory = _opd_entry("Directory", 0, 24 * (len(blocks) + 1)) + b"".join(
        _opd_entry(name, kind, len(payload)) for name, kind, payload in blocks)
    with open(path, "wb") as f:
        f.write(b"\x01\x00" + directory + b"".join(p for _, _, p in blocks))


def write_xyz(path, z, dx, dy, unit="um"):
    nx, ny = z.shape
    rows = [f"{i * dx:.12g} {j * dy:.12g} {z[i, j]:.12g}"
            for j in range(ny) for i in range(nx)]
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"# x y z\n# units = {unit}\n" + "\n".join(rows) + "\n")


def write_netcdf_heights(path, z, dx, dy):
    import xarray as xr

    nx, ny = z.shape
    ds = xr.Dataset({"heights": (("x1", "x2"), z, {"units": "um"})},
                    coords={"x1": ("x1", np.arange(nx) * dx, {"units": "um"}),
                            "x2": ("x2", np.arange(ny) * dy, {"units": "um"})})
    ds.to_netcdf(path)


WRITERS = {"x3p": write_x3p, "sdf": write_sdf, "sur": write_sur, "plu": write_plu,
           "opd": write_opd, "xyz": write_xyz, "nc": write_netcdf_heights}
