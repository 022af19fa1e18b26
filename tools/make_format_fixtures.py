#!/usr/bin/env python3
"""Write the demo campaign (fixtures/campaigns/one-sided-demo) in the loggers' formats.

Independent writers, not rocklab: openpyxl (.xlsx), npTDMS (.tdms), scipy.io (MAT v5),
h5py (MAT v7.3 = HDF5 with MATLAB's 512-byte user block) and pyarrow (.parquet). Every
value is the CSV's text parsed by Python's float() (correctly rounded, as Rust's parse),
so a reduction of each copy must give exactly the CSV's numbers (tests/formats.rs).

Each format gets fixtures/formats/<format>/ with the logs and a campaign.toml equal to
the CSV campaign's but for the file names and the format's own keys:
- xlsx: test 150_1's workbook has an 'info' sheet first and the data on sheet 'log'
  (the manifest names it); the others have the data on their first sheet.
- tdms: channels in group 'demo'; test 150_1's file also has a group 'raw' with a
  channel of the same name (the manifest names the group). Plus waveform/150_1.tdms:
  only the displacement channel, time from wf_start_offset/wf_increment.
- mat5: column vectors time_s, disp_mm, acc_g (scipy.io.savemat).
- mat73: the same as MATLAB 7.3 stores them (HDF5 datasets of shape (1, n), attribute
  MATLAB_class = 'double', a 512-byte user block with MATLAB's header text).
- parquet: columns time_s, disp_mm, acc_g (pyarrow, snappy).

Run from the repository root: python3 tools/make_format_fixtures.py
Needs: pip install openpyxl nptdms pyarrow h5py scipy numpy
"""

import csv
import pathlib
import re

import h5py
import numpy as np
import openpyxl
import pyarrow as pa
import pyarrow.parquet as pq
import scipy.io
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

ROOT = pathlib.Path(__file__).resolve().parent.parent
SRC = ROOT / "fixtures" / "campaigns" / "one-sided-demo"
OUT = ROOT / "fixtures" / "formats"
COLUMNS = ["time_s", "disp_mm", "acc_g"]


def read_csv(path):
    """The CSV's header and columns, every value float(text)."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header, body = rows[0], rows[1:]
    assert header == COLUMNS, header
    return {name: np.array([float(r[i]) for r in body]) for i, name in enumerate(header)}


def write_xlsx(path, cols, with_info_sheet):
    wb = openpyxl.Workbook()
    ws = wb.active
    if with_info_sheet:
        ws.title = "info"
        ws.append(["campaign", "one-sided-demo"])
        ws.append(["note", "the data are on sheet 'log'"])
        ws = wb.create_sheet("log")
    else:
        ws.title = "data"
    ws.append(COLUMNS)
    for row in zip(*(cols[c] for c in COLUMNS)):
        ws.append([float(v) for v in row])
    wb.save(path)


def write_tdms(path, cols, with_raw_group):
    objects = [RootObject(properties={"campaign": "one-sided-demo"}), GroupObject("demo")]
    objects += [ChannelObject("demo", c, cols[c]) for c in COLUMNS]
    if with_raw_group:
        objects += [GroupObject("raw"), ChannelObject("raw", "disp_mm", cols["disp_mm"] * 0.0 + 1.0)]
    with TdmsWriter(str(path)) as w:
        w.write_segment(objects)


def write_tdms_waveform(path, cols):
    t = cols["time_s"]
    dt = 0.005
    assert np.allclose(np.diff(t), dt, atol=1e-12)
    props = {"wf_start_offset": float(t[0]), "wf_increment": dt, "unit_string": "mm"}
    with TdmsWriter(str(path)) as w:
        w.write_segment([GroupObject("demo"), ChannelObject("demo", "disp_mm", cols["disp_mm"], properties=props)])


def write_mat5(path, cols):
    scipy.io.savemat(str(path), {c: cols[c] for c in COLUMNS}, oned_as="column", do_compression=False)


def write_mat73(path, cols):
    with h5py.File(str(path), "w", userblock_size=512) as f:
        for c in COLUMNS:
            d = f.create_dataset(c, data=cols[c].reshape(1, -1))
            d.attrs["MATLAB_class"] = np.bytes_(b"double")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Nov 23 00:00:00 2026 HDF5 schema 1.00 ."
    block = header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    block = block.ljust(512, b"\x00")
    with open(path, "r+b") as f:
        f.write(block)


def write_parquet(path, cols):
    pq.write_table(pa.table({c: cols[c] for c in COLUMNS}), str(path))


def write_bad(d):
    """Small files with one defect each, for the located errors (tests/formats.rs)."""
    d.mkdir(parents=True, exist_ok=True)
    t = [0.0, 0.005, 0.010, 0.015, 0.020, 0.025, 0.030, 0.035]
    x = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5]
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "log"
    ws.append(["time_s", "disp_mm"])
    for i, (a, b) in enumerate(zip(t, x)):
        ws.append([a, "n/a" if i == 3 else b])  # sheet row 5, column B
    wb.save(d / "text_cell.xlsx")
    pq.write_table(pa.table({"time_s": t, "disp_mm": x[:6] + [float("nan")] + x[7:]}), str(d / "nan.parquet"))
    scipy.io.savemat(str(d / "time_back.mat"), {"time_s": np.array(t[:3] + [0.001] + t[4:]), "disp_mm": np.array(x)}, oned_as="column")
    scipy.io.savemat(str(d / "matrix.mat"), {"time_s": np.array(t), "disp_mm": np.ones((2, 4))})


def manifest(ext, extra_150_1):
    text = (SRC / "campaign.toml").read_text()
    text = re.sub(r'file = "([^"]+)\.csv"', lambda m: f'file = "{m.group(1)}.{ext}"', text)
    text = text.replace("# Synthetic", f"# The CSV demo campaign as .{ext} files (tools/make_format_fixtures.py).\n# Synthetic", 1)
    if extra_150_1:
        text = text.replace(f'file = "150_1.{ext}"', f'file = "150_1.{ext}"\n{extra_150_1}', 1)
    return text


def main():
    tests = sorted(p.stem for p in SRC.glob("*.csv"))
    data = {t: read_csv(SRC / f"{t}.csv") for t in tests}
    formats = {
        "xlsx": ("xlsx", 'sheet = "log"', lambda p, c, t: write_xlsx(p, c, t == "150_1")),
        "tdms": ("tdms", 'group = "demo"', lambda p, c, t: write_tdms(p, c, t == "150_1")),
        "mat5": ("mat", None, lambda p, c, t: write_mat5(p, c)),
        "mat73": ("mat", None, lambda p, c, t: write_mat73(p, c)),
        "parquet": ("parquet", None, lambda p, c, t: write_parquet(p, c)),
    }
    for name, (ext, extra, write) in formats.items():
        d = OUT / name
        d.mkdir(parents=True, exist_ok=True)
        for t in tests:
            write(d / f"{t}.{ext}", data[t], t)
        (d / "campaign.toml").write_text(manifest(ext, extra))
    write_bad(OUT / "bad")
    w = OUT / "waveform"
    w.mkdir(parents=True, exist_ok=True)
    write_tdms_waveform(w / "150_1.tdms", data["150_1"])


if __name__ == "__main__":
    main()
