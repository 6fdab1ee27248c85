#!/usr/bin/env python3
"""How processing and fitting grow with texels and dots (docs/benchmarks.md, issue 19).

Simulates a preset's rig once per dot grid (`svbtdf simulate --dots NxN`, the same span of the
screen more or less densely; cached as paper_scale.py caches its simulation), then processes each session onto every texel grid (`bench_process SIM THREADS T
T --keep STORE`, the true calibration) and fits the store with default options (`svbtdf fit`).
Prints one table (each stage's wall time, the fit's CPU time and the peak memory), the exponents
of time against texels and against dots, and what they predict for a larger session.

  bench/scaling.py [--preset grid-sheet] [--dots 20 40] [--texels 150 300 600] [--cache DIR]
                   [--build build] [--threads N] [--predict 2000 40]

Each run's stores and materials go to DIR/scaling-TIMESTAMP (removed unless --keep). Every cell is
printed as soon as it is measured and appended to cells.jsonl there (a torn last line is ignored),
so that an interrupted run keeps what it measured: `--resume DIR/scaling-TIMESTAMP` measures only
the missing cells. The table is written there as scaling.json.
"""

import argparse
import datetime
import json
import math
import os
import shutil
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paper_scale import duration, number_after, run_stage, simulate_once  # noqa: E402


def slope(xs, ys):
    """Least-squares slope of ln y against ln x: the exponent of a power law."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def simulation_for(svbtdf, preset, dots, cache):
    """The cached session of `preset` captured with a dots x dots grid."""
    return simulate_once(svbtdf, preset, cache / f"{preset}-dots{dots}x{dots}", ["--dots", f"{dots}x{dots}"])


def fit_stages(material):
    """The fit's three stages' wall times, as `svbtdf fit` records them in the material."""
    statistics = json.loads((material / "material.json").read_text())["provenance"]["statistics"]
    return {"clustering_s": statistics["clustering_seconds"], "representatives_s": statistics["fit_seconds"],
            "refine_s": statistics["refine_seconds"]}


def read_cells(journal):
    """The cells measured so far: one JSON object a line; a torn last line (a run killed while
    writing it) is dropped."""
    cells = []
    if journal.is_file():
        for line in journal.read_text().splitlines():
            try:
                cells.append(json.loads(line))
            except json.JSONDecodeError:
                break
    return cells


def append_cell(journal, cell):
    with open(journal, "a") as f:
        f.write(json.dumps(cell) + "\n")
        f.flush()
        os.fsync(f.fileno())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="grid-sheet")
    parser.add_argument("--dots", type=int, nargs="+", default=[20, 40], help="dots per side of each grid")
    parser.add_argument("--texels", type=int, nargs="+", default=[150, 300, 600], help="texels per side of each grid")
    parser.add_argument("--cache", type=Path, default=Path(os.environ.get("SVBTDF_BENCH_CACHE", Path.home() / ".cache/svbtdf-bench")))
    parser.add_argument("--build", type=Path, default=Path(__file__).resolve().parent.parent / "build")
    parser.add_argument("--threads", type=int, default=0, help="worker threads (0: all cores)")
    parser.add_argument("--predict", type=int, nargs=2, default=[2000, 40], metavar=("TEXELS", "DOTS"),
                        help="texels and dots per side of the session to predict")
    parser.add_argument("--keep", action="store_true", help="keep the stores and materials")
    parser.add_argument("--resume", type=Path, help="an earlier run's folder: measure only the cells it lacks")
    args = parser.parse_args()
    if len(args.texels) < 2 and len(args.dots) < 2:
        sys.exit("scaling: needs two or more texel grids or dot grids to measure a growth")

    svbtdf = args.build / "cli/svbtdf"
    bench_process = args.build / "bench/bench_process"
    for tool in (svbtdf, bench_process):
        if not tool.is_file():
            sys.exit(f"scaling: {tool} is missing (cmake --build {args.build} --target svbtdf bench)")
    run = args.resume or args.cache / ("scaling-" + datetime.datetime.now().strftime("%Y%m%d-%H%M%S"))
    run.mkdir(parents=True, exist_ok=args.resume is not None)
    journal = run / "cells.jsonl"
    cells = read_cells(journal)
    for dots in sorted(args.dots):
        if all(any(c["texels"] == t and c["dots"] == dots for c in cells) for t in args.texels):
            continue
        simulated, simulate = simulation_for(svbtdf, args.preset, dots, args.cache)
        for texels in sorted(args.texels):
            if any(c["texels"] == texels and c["dots"] == dots for c in cells):
                continue
            name = f"{texels}x{texels}-dots{dots}"
            store, material = run / name / "processed", run / name / "material"
            shutil.rmtree(run / name, ignore_errors=True)  # an interrupted cell's, measured again
            store.parent.mkdir()
            process = run_stage(f"process {name}", [bench_process, simulated, args.threads, texels, texels, "--keep", store],
                                capture=True)
            fit = run_stage(f"fit {name}", [svbtdf, "fit", store, "--out", material, "--threads", args.threads])
            cell = {
                "texels": texels, "dots": dots,
                "simulate_wall_s": simulate["wall_s"],
                "decode_s": number_after("baseline, read every image once:", process["output"]),
                "process_s": number_after("process:", process["output"]),
                "process_peak_mb": process["peak_mb"],
                "fit_s": fit["wall_s"], "fit_cpu_s": fit["cpu_s"], "fit_peak_mb": fit["peak_mb"],
                **fit_stages(material),
                "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            }
            append_cell(journal, cell)
            cells.append(cell)
            print(f"scaling: {name}: decode {duration(cell['decode_s'])}, process {duration(cell['process_s'])}, "
                  f"fit {duration(cell['fit_s'])} (CPU {duration(cell['fit_cpu_s'])})", flush=True)
            if not args.keep:
                shutil.rmtree(run / name)
    cells = [c for c in cells if c["texels"] in args.texels and c["dots"] in args.dots]
    cells.sort(key=lambda c: (c["dots"], c["texels"]))

    print()
    print(f"{args.preset}: {os.cpu_count()} cores, {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}")
    print("| texels | dots | decode once | process | fit | clustering / representatives / refinement | fit CPU | "
          "process + fit | peak memory |")
    print("|---|---|---|---|---|---|---|---|---|")
    for c in cells:
        peak = max(m for m in (c["process_peak_mb"], c.get("fit_peak_mb")) if m is not None)
        cpu = duration(c["fit_cpu_s"]) if c.get("fit_cpu_s") is not None else "-"
        stages = " / ".join(duration(c[k]) if c.get(k) is not None else "-"
                            for k in ("clustering_s", "representatives_s", "refine_s"))
        print(f"| {c['texels']}^2 | {c['dots']}^2 | {duration(c['decode_s'])} | {duration(c['process_s'])} | "
              f"{duration(c['fit_s'])} | {stages} | {cpu} | {duration(c['process_s'] + c['fit_s'])} | {peak:.0f} MB |")

    exponents = {}
    print("\nexponents (time ~ count^e, least squares in log-log; counts are texels and dots, not per side):")
    for stage in ("process_s", "fit_s", "clustering_s", "representatives_s", "refine_s"):
        for axis, held in (("texels", "dots"), ("dots", "texels")):
            for value in sorted({c[held] for c in cells}):
                line = [c for c in cells if c[held] == value]
                if len(line) >= 2 and all(c.get(stage) is not None for c in line):
                    e = slope([c[axis] ** 2 for c in line], [c[stage] for c in line])
                    exponents[f"{stage} vs {axis} at {value}^2 {held}"] = e
                    print(f"  {stage[:-2]:15s} against {axis} at {value}^2 {held}: {e:.2f}")

    # The prediction: from the largest measured cell, each stage scaled by its exponents at that
    # cell's dots and texels.
    largest = max(cells, key=lambda c: (c["texels"], c["dots"]))
    want_texels, want_dots = args.predict
    predicted = {}
    for stage in ("process_s", "fit_s"):
        t = largest[stage]
        e_texels = exponents.get(f"{stage} vs texels at {largest['dots']}^2 dots")
        e_dots = exponents.get(f"{stage} vs dots at {largest['texels']}^2 texels")
        if e_texels is not None:
            t *= (want_texels / largest["texels"]) ** (2 * e_texels)
        if e_dots is not None:
            t *= (want_dots / largest["dots"]) ** (2 * e_dots)
        predicted[stage] = t
    print(f"\npredicted for {want_texels}^2 texels and {want_dots}^2 dots on this machine: process "
          f"{duration(predicted['process_s'])}, fit {duration(predicted['fit_s'])} (from the {largest['texels']}^2, "
          f"{largest['dots']}^2 cell)")
    summary = {"preset": args.preset, "cells": cells, "exponents": exponents,
               "prediction": {"texels": want_texels, "dots": want_dots, **predicted}}
    (run / "scaling.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"written: {run / 'scaling.json'}")


if __name__ == "__main__":
    main()
