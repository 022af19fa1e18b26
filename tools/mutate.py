#!/usr/bin/env python3
"""Mutation driver of issue 22 (not run by CI; docs/hardening.md).

Makes N mutated inputs from the fixtures — displacement logs and campaign
manifests (`reduce`), the loggers' binary formats (TDMS, MAT v5 and v7.3,
Parquet, Excel: byte flips, truncation, zeroed blocks, `reduce`), `[acquisition]`
tables with hostile values (`reduce`), campaigns to `calibrate`, reductions'
summary.json for `archive add`, ground-motion records and block files
(`simulate`), study files (`facade`), restitution law files (`facade`, session 13)
and logs for `init` (session 13) — of the kinds that found the defects of issue 22: scaled
columns, huge/tiny/NaN/inf values, path-like names, NUL, truncation, long cells,
wrong types. Runs the release binary on each in a fresh sandbox folder with a
20 s limit and a 2 GiB address-space cap (`ulimit -v`), and checks:

  crash     killed by a signal, or a Rust panic (exit 101 / "panicked at")
  hang      not finished in 20 s
  nonfinite NaN/inf in an output of a run that exits 0 (CSV fields, words of
            Markdown/LaTeX/HTML/SVG, NaN/Infinity or a null number in JSON)
  escape    a file created or changed outside --out
  modified  an input file changed

Usage: cargo build --release && python3 tools/mutate.py --seed 7 --n 1500 [--jobs 2]
Prints one line per failing case (kind, mutation, check, stderr excerpt), then
the counts. Exit status 1 if any case failed a check.
"""

import argparse
import hashlib
import json
import os
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FIX = ROOT / "fixtures"
BIN = ROOT / "target" / "release" / "rocklab"
LIMIT_S = 20
AS_BYTES = 2 * 1024**3

TOKENS = ["NaN", "nan", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e-308", "1e-300", "1e300", "0", "-0",
          "1e30", "\0", "..", "/", "../../x", "/../../escaped", "\\", ",", ";", "\t", "\n", "\r\n", '"', "#", "=",
          "[", "]", "{", "}", "true", '"text"', "[1, 2]", "99999999999999999999999", "1,5", "", "\ufeff", "é"]
NAMES = ["../../escaped", "/../../escaped", "/tmp/rocklab-escaped", "a/b", "a\\\\b", "a\\u0000b", "..", ".", "",
         "x" * 300, ".hidden", "CON", "a\\nb"]
FACTORS = [1e-300, 1e-6, 1e-3, -1.0, 0.0, 1e3, 1e6, 1e30, 1e300, 1e308]
NUM = re.compile(rb"-?\d+(\.\d*)?([eE][-+]?\d+)?")


def mutate_bytes(rng, b, kind):
    """One mutation of bytes `b`; returns (bytes, description)."""
    ops = ["replace", "insert", "delete", "truncate", "long", "scale", "nul", "number"]
    if kind == "toml":
        ops += ["name", "value", "value", "type"]
    op = rng.choice(ops)
    p = rng.randrange(len(b) + 1) if b else 0
    if op == "replace":
        t = rng.choice(TOKENS).encode()
        n = rng.randrange(8)
        return b[:p] + t + b[p + n:], f"replace@{p}+{n}:{t!r}"
    if op == "insert":
        t = rng.choice(TOKENS).encode()
        return b[:p] + t + b[p:], f"insert@{p}:{t!r}"
    if op == "delete":
        n = rng.randrange(1, 200)
        return b[:p] + b[p + n:], f"delete@{p}+{n}"
    if op == "truncate":
        return b[:p], f"truncate@{p}"
    if op == "long":
        n = rng.choice([1000, 70000, 1_000_000, 8_000_000])
        return b[:p] + b"7" * n + b[p:], f"long@{p}:{n}"
    if op == "nul":
        return b[:p] + b"\0" + b[p:], f"nul@{p}"
    if op == "number":
        nums = list(NUM.finditer(b))
        if not nums:
            return b, "number:none"
        m = rng.choice(nums)
        t = rng.choice(["NaN", "inf", "-inf", "1e308", "-1e308", "1e-308", "1e300", "1e-300", "0", "-1", "1e30"]).encode()
        return b[:m.start()] + t + b[m.end():], f"number@{m.start()}:{t!r}"
    if op == "scale":
        return scale_column(rng, b)
    if op == "name":
        name = rng.choice(NAMES)
        new, n = re.subn(rb'((?:^|\n)\s*(?:name|id)\s*=\s*)"[^"\n]*"', lambda m: m.group(1) + b'"' + name.encode() + b'"', b,
                         count=rng.randrange(1, 4))
        return new, f"name:{name!r}x{n}"
    if op == "value":
        keys = re.findall(rb"(?m)^\s*([A-Za-z_0-9]+)\s*=\s*(-?[\d.eE+-]+)\s*$", b)
        if not keys:
            return b, "value:none"
        k, _ = rng.choice(keys)
        v = rng.choice(["1e308", "1e-308", "-1", "0", "1e300", "1e-300", "nan", "inf", "-inf", "1e30", "1e6", "1e-6"])
        new = re.sub(rb"(?m)^(\s*" + re.escape(k) + rb"\s*=\s*)(-?[\d.eE+-]+)\s*$", lambda m: m.group(1) + v.encode(), b, count=1)
        return new, f"value:{k.decode()}={v}"
    if op == "type":
        keys = re.findall(rb"(?m)^\s*([A-Za-z_0-9]+)\s*=", b)
        if not keys:
            return b, "type:none"
        k = rng.choice(keys)
        v = rng.choice(['"text"', "[1, 2]", "true", "{ a = 1 }", "[[1]]", '"' + "x" * 100000 + '"'])
        new = re.sub(rb"(?m)^(\s*" + re.escape(k) + rb"\s*=\s*)(.*)$", lambda m: m.group(1) + v.encode(), b, count=1)
        return new, f"type:{k.decode()}={v[:20]}"
    raise AssertionError(op)


def scale_column(rng, b):
    """Multiply one column of the numeric rows (or every number) by a factor."""
    f = rng.choice(FACTORS)
    col = rng.randrange(4)
    out = []
    for line in b.split(b"\n"):
        sep = b"," if b"," in line else None
        cells = line.split(sep)
        if col < len(cells):
            try:
                v = float(cells[col])
                cells[col] = repr(v * f).encode()
            except ValueError:
                pass
        out.append((sep or b" ").join(cells))
    return b"\n".join(out), f"scale:col{col}x{f}"


def case_inputs(rng, sandbox):
    """Write one case's inputs into `sandbox/work` and return (kind, description, argv)."""
    work = sandbox / "work"
    kind = rng.choice(["log", "manifest", "record", "block", "study", "format", "acquisition", "calibrate", "archive",
                       "law", "init"])
    out = work / "out" / "o"
    if kind in ("format", "acquisition", "calibrate", "archive"):
        return newer_case(rng, work, out, kind)
    if kind == "init":
        # `init` writes DIR/campaign.toml beside the logs: its --out is the folder.
        camp = rng.choice(["one-sided-demo", "two-sided-demo", "mujoco-public-one-sided", "daq-public-bessel-1"])
        shutil.copytree(FIX / "campaigns" / camp, out)
        for extra in ("campaign.toml", "truth.json"):
            (out / extra).unlink(missing_ok=True)
        target = rng.choice(sorted(out.glob("*.csv")))
        desc = mutate_file(rng, target, "text")
        return kind, f"{camp}/{target.name} {desc}", ["init", str(out)]
    if kind in ("log", "manifest"):
        camp = rng.choice(["one-sided-demo", "two-sided-demo"])
        shutil.copytree(FIX / "campaigns" / camp, work / "c")
        (work / "c" / "truth.json").unlink()
        target = work / "c" / ("campaign.toml" if kind == "manifest" else rng.choice(sorted(p.name for p in (work / "c").glob("*.csv"))))
        desc = mutate_file(rng, target, "toml" if kind == "manifest" else "text")
        argv = ["reduce", str(work / "c" / "campaign.toml"), "--out", str(out)]
        if rng.random() < 0.3:
            argv.append("--no-plots")
        return kind, f"{camp}/{target.name} {desc}", argv
    shutil.copytree(FIX / "facade", work / "f")
    shutil.copytree(FIX / "ground-motions", work / "ground-motions")
    study = (work / "f" / "study.toml").read_text()
    study = re.sub(r"(?m)^samples = \d+", "samples = " + str(rng.choice([0, 0, 0, 5])), study)
    if kind == "law":
        # A coefficient set read from a restitution law file (a law alone or a
        # summary.json holding one), the file mutated; drawn in the ensembles.
        law = (FIX / "facade" / "law.json").read_text()
        # Half of them a one-sided law with its pushes' Ω/p, read by the impact's
        # speed (fifty-seventh session).
        by_speed = rng.random() < 0.5
        # A quarter of those keep the fixture as it is: sides fitted apart, a
        # free-arc outward curve, no Ω/p, which a set read by speed refuses
        # (fifty-eighth session).
        if by_speed and rng.random() < 0.75:
            doc = json.loads(law)
            doc["parameters"]["out"]["g"] = "push"
            doc["parameters"]["push_speed"] = {"median": 16.9, "range": [13.5, 18.0], "impacts": 13}
            law = json.dumps(doc, indent=1)
        if rng.random() < 0.5:
            law = '{"campaign": "c", "restitution_law": ' + law + "}"
        (work / "f" / "law.json").write_text(law)
        desc = mutate_file(rng, work / "f" / "law.json", rng.choice(["toml", "text"]))
        study += '\n[[coefficients]]\nname = "law"\nlaw = "law.json"\n' + ('reading = "speed"\n' if by_speed else "")
        (work / "f" / "study.toml").write_text(study)
        return kind, f"law.json {desc}", ["facade", str(work / "f" / "study.toml"), "--out", str(out)]
    (work / "f" / "study.toml").write_text(study)
    record = rng.choice(["synthetic/one_sine_pulse_nga.AT2", "synthetic/one_sine_pulse_old.AT2",
                         "esm-central-italy-2016/IT.NRC..HGE.D.20160824.013632.C.ACC.ASC"])
    if kind == "record":
        desc = mutate_file(rng, work / "ground-motions" / record, "text")
        argv = ["simulate", "--block", str(work / "f" / "block.toml"), "--record", str(work / "ground-motions" / record),
                "--e", "0.9", "--out", str(out)]
        return kind, f"{record} {desc}", argv
    if kind == "block":
        desc = mutate_file(rng, work / "f" / "block.toml", "toml")
        if rng.random() < 0.5:
            argv = ["simulate", "--block", str(work / "f" / "block.toml"), "--record", str(work / "ground-motions" / record),
                    "--e", "0.9", "--out", str(out)]
        else:
            argv = ["facade", str(work / "f" / "study.toml"), "--out", str(out)]
        return kind, f"block.toml {desc}", argv
    desc = mutate_file(rng, work / "f" / "study.toml", "toml")
    argv = ["facade", str(work / "f" / "study.toml"), "--out", str(out)]
    if rng.random() < 0.3:
        argv += ["--scales", rng.choice(["0.5:1.5:3", "1e-300:1e300:3", "1:2:100000000", "nan:1:3", "0.5:1:2"])]
    return kind, f"study.toml {desc}", argv


FORMATS = ["tdms", "mat5", "mat73", "parquet", "xlsx"]
FILTERS = ['"none"', '"bessel"', '"butterworth"', '"unknown"', '"fir"', '""', "4", '"../../x"']


def mutate_binary(rng, b):
    """One mutation of a binary file: flipped bytes, a zeroed or 0xFF block,
    truncation, a duplicated chunk; returns (bytes, description)."""
    op = rng.choice(["flip", "block", "truncate", "dup", "flip"])
    p = rng.randrange(max(len(b), 1))
    if op == "flip":
        n = rng.choice([1, 4, 32])
        bb = bytearray(b)
        for _ in range(n):
            q = rng.randrange(len(bb))
            bb[q] ^= 1 << rng.randrange(8)
        return bytes(bb), f"flip x{n}"
    if op == "block":
        n, v = rng.choice([8, 64, 4096]), rng.choice([b"\0", b"\xff"])
        return b[:p] + v * n + b[p + n:], f"block@{p}+{n}:{v!r}"
    if op == "truncate":
        return b[:p], f"truncate@{p}"
    n = rng.randrange(1, 4096)
    return b[:p] + b[p:p + n] * rng.choice([2, 100]) + b[p + n:], f"dup@{p}+{n}"


def acquisition_table(rng):
    """An [acquisition] table (or per-test inline one) with hostile values."""
    order = rng.choice(["4", "0", "-1", "1e9", "2.5", "99", '"four"', "nan"])
    cut = rng.choice(["50.0", "0", "-1", "1e308", "nan", "inf", "1e-300", "99999", '"fast"', "100"])
    return f"filter = {rng.choice(FILTERS)}\norder = {order}\ncutoff_hz = {cut}\n", f"order={order} cutoff={cut}"


def newer_case(rng, work, out, kind):
    """Cases for what came after the first mutation runs: binary formats,
    [acquisition], calibrate, archive add."""
    if kind == "format":
        fmt = rng.choice(FORMATS)
        shutil.copytree(FIX / "formats" / fmt, work / "c")
        target = rng.choice(sorted(p for p in (work / "c").iterdir() if p.name != "campaign.toml"))
        b, descs = target.read_bytes(), []
        for _ in range(rng.choice([1, 1, 2])):
            b, d = mutate_binary(rng, b)
            descs.append(d)
        target.write_bytes(b)
        return kind, f"{fmt}/{target.name} {'; '.join(descs)}", ["reduce", str(work / "c" / "campaign.toml"), "--out", str(out), "--no-plots"]
    camp = rng.choice(["one-sided-demo", "two-sided-demo"])
    shutil.copytree(FIX / "campaigns" / camp, work / "c")
    (work / "c" / "truth.json").unlink()
    manifest = work / "c" / "campaign.toml"
    if kind == "acquisition":
        table, desc = acquisition_table(rng)
        text = manifest.read_text()
        if rng.random() < 0.5:
            text = text.replace("[[test]]", "[acquisition]\n" + table + "\n[[test]]", 1)
        else:
            inline = "acquisition = { " + table.strip().replace("\n", ", ") + " }\n"
            text = re.sub(r"(?m)^(file = .*\n)", lambda m: m.group(1) + inline, text, count=1)
        manifest.write_text(text)
        return kind, f"{camp} {desc}", ["reduce", str(manifest), "--out", str(out), "--no-plots"]
    if kind == "calibrate":
        target = rng.choice([manifest] + sorted((work / "c").glob("*.csv")))
        desc = mutate_file(rng, target, "toml" if target == manifest else "text")
        return kind, f"{camp}/{target.name} {desc}", ["calibrate", str(manifest), "--out", str(out)]
    # archive: a reduction's summary.json, mutated, added to an archive under out.
    red = work / "red"
    subprocess.run([str(BIN), "reduce", str(manifest), "--out", str(red), "--no-plots"], capture_output=True, timeout=LIMIT_S)
    desc = mutate_file(rng, red / "summary.json", rng.choice(["toml", "text"]))
    return kind, f"{camp} summary.json {desc}", ["archive", "add", "--to", str(out), str(red)]


def mutate_file(rng, path, kind):
    b = path.read_bytes()
    descs = []
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        b, d = mutate_bytes(rng, b, kind)
        descs.append(d)
    path.write_bytes(b)
    return "; ".join(descs)


def snapshot(d):
    """path -> sha256 of every file below d."""
    snap = {}
    for p in d.rglob("*"):
        if p.is_file() and not p.is_symlink():
            snap[p] = hashlib.sha256(p.read_bytes()).hexdigest()
    return snap


def limit():
    resource.setrlimit(resource.RLIMIT_AS, (AS_BYTES, AS_BYTES))


NUMERIC_JSON = {"pga_g", "pgv_cm_s", "max_theta_over_alpha", "min_theta_over_alpha", "alpha_rad", "p2_per_s2",
                "i0_kg_m2", "mass_kg", "r_m", "e_in", "e_out", "scale", "rtol", "atol", "magnification", "e_housner"}


def non_finite(path):
    """A description of the first non-finite number in an output, or None."""
    data = path.read_bytes()
    ext = path.suffix
    if ext == ".json":
        text = data.decode("utf-8", "replace")
        # NaN/Infinity as number tokens only: an echoed input string may hold the
        # word (seed 28: a block named "… (Table NaN)" was reported as a NaN).
        constants = []
        try:
            doc = json.loads(text, parse_constant=lambda c: constants.append(c) or float(c))
        except ValueError as e:
            return f"invalid JSON: {e}"
        if constants:
            return f"{constants[0]} in JSON"
        bad = []

        def walk(v, key, path):
            if isinstance(v, dict):
                for k, x in v.items():
                    # [uncertainty]'s inputs are optional distributions, null when not drawn.
                    if k != "uncertainty":
                        walk(x, k, f"{path}.{k}")
            elif isinstance(v, list):
                for i, x in enumerate(v):
                    walk(x, key, f"{path}[{i}]")
            elif v is None and key in NUMERIC_JSON and not (key == "e_housner" and ".law." in path):
                # (a law set's e_housner is null when e_H is Eq. 2's, by design)
                bad.append(path)
        walk(doc, "", "")
        return f"null {bad[0]} in JSON" if bad else None
    if ext not in (".csv", ".md", ".tex", ".html", ".svg"):
        return None
    text = data.decode("utf-8", "replace")
    # Where numbers are written: CSV fields, table cells (Markdown |, LaTeX &,
    # HTML <td>), SVG attribute values; not prose, labels or echoed inputs.
    for i, line in enumerate(text.splitlines()):
        if ext == ".csv":
            cells = [f.strip('"') for f in line.split(",")]
        elif ext == ".md":
            cells = line.split("|") if line.lstrip().startswith("|") else []
        elif ext == ".tex":
            cells = [c.strip().rstrip("\\") for c in line.split("&")] if "&" in line else []
        elif ext == ".html":
            cells = re.findall(r"<td[^>]*>(.*?)</td>", line)
        else:
            cells = [w for v in line.split('"')[1::2] for w in re.split(r"[ ,]", v)]
        for c in cells:
            if re.match(r"^[-+−]?(nan|infinity|inf)($|[ %$°])", c.strip().lower()):
                return f"line {i + 1}: {line[:80]}"
    return None


def run_case(seed, i):
    rng = random.Random(f"{seed}:{i}")
    base = Path(tempfile.mkdtemp(prefix="rocklab-mut-"))
    try:
        sandbox = base / "s"
        (sandbox / "work").mkdir(parents=True)
        kind, desc, argv = case_inputs(rng, sandbox)
        out = sandbox / "work" / "out" / "o"
        inputs = snapshot(sandbox)
        try:
            p = subprocess.run([str(BIN)] + argv, cwd=sandbox / "work", capture_output=True, timeout=LIMIT_S,
                               preexec_fn=limit)
            code, stderr = p.returncode, p.stderr.decode("utf-8", "replace")
        except subprocess.TimeoutExpired as e:
            code, stderr = None, (e.stderr or b"").decode("utf-8", "replace")
        problems = []
        if code is None:
            problems.append("hang")
        elif code < 0 or code == 101 or "panicked at" in stderr:
            problems.append(f"crash({code})")
        after = snapshot(base)
        for p_, h in after.items():
            if p_ in inputs:
                if inputs[p_] != h:
                    problems.append(f"modified {p_.relative_to(sandbox)}")
            elif out not in p_.parents:
                problems.append(f"escape {p_.relative_to(base)}")
        for p_ in inputs:
            if p_ not in after:
                problems.append(f"modified (deleted) {p_.relative_to(sandbox)}")
        if code == 0:
            for p_ in after:
                # (init's --out holds its inputs, the logs: only what the run wrote)
                if out in p_.parents and p_ not in inputs:
                    nf = non_finite(p_)
                    if nf:
                        problems.append(f"nonfinite {p_.name}: {nf}")
        long_msg = len(stderr) > 65536
        if long_msg:
            problems.append(f"longmsg {len(stderr)} bytes")
        return kind, desc, argv[0], code, problems, stderr.strip().splitlines()[-1][:200] if stderr.strip() else "", long_msg
    finally:
        shutil.rmtree(base, ignore_errors=True)
        # A hostile absolute name must not have landed in /tmp either.
        for stray in ("/tmp/rocklab-escaped", "/tmp/rocklab-escaped.png", "/tmp/rocklab-escaped.svg"):
            if os.path.exists(stray):
                print(f"ESCAPE: {stray} exists", file=sys.stderr)


def main():
    global BIN
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=2022)
    ap.add_argument("--n", type=int, default=1500)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--bin", type=Path, default=BIN, help="the binary to run (default target/release/rocklab)")
    a = ap.parse_args()
    BIN = a.bin.resolve()  # the cases run with their sandbox as the working folder
    if not BIN.exists():
        sys.exit(f"{BIN} not found: cargo build --release")
    counts = {"cases": 0, "exit0": 0, "exit2": 0, "other_exit": 0, "crash": 0, "hang": 0, "nonfinite": 0, "escape": 0,
              "modified": 0, "longmsg": 0, "messages_over_64KiB": 0}
    by_kind, codes = {}, {}
    with ThreadPoolExecutor(max_workers=a.jobs) as pool:
        for kind, desc, cmd, code, problems, last, long_msg in pool.map(lambda i: run_case(a.seed, i), range(a.n)):
            counts["cases"] += 1
            by_kind[kind] = by_kind.get(kind, 0) + 1
            codes[str(code)] = codes.get(str(code), 0) + 1
            if code == 0:
                counts["exit0"] += 1
            elif code == 2:
                counts["exit2"] += 1
            else:
                counts["other_exit"] += 1
            counts["messages_over_64KiB"] += long_msg
            for pr in problems:
                counts[pr.split("(")[0].split(" ")[0]] += 1
            if problems:
                print(f"FAIL [{kind} {cmd}] {desc!r}: {', '.join(problems)} | {last}", flush=True)
    print(json.dumps({"seed": a.seed, **counts, "by_kind": by_kind, "exit_codes": codes}, indent=1))
    bad = sum(counts[k] for k in ("crash", "hang", "nonfinite", "escape", "modified"))
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
