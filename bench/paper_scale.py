#!/usr/bin/env python3
"""The whole chain at paper scale, timed stage by stage (docs/benchmarks.md, issue 19).

Simulates a preset once into a cache folder (the slowest stage, and the same session for every
later run), then times processing it against reading and decoding every image once
(bench_process, in the same run), fitting the processed store with `svbtdf fit` against the
single-thread projections of bench_fit and bench_refine (run just before it), and compares the
fitted material with the truth. Prints one table: each stage's wall time, CPU time, peak
resident memory and its ratio to its baseline; writes the same as JSON next to the cache.

  bench/paper_scale.py [--preset grid-sheet] [--cache DIR] [--build build] [--threads N]

The simulation is kept in DIR/PRESET/simulated (default DIR: ~/.cache/svbtdf-bench); delete it
to simulate again. Each run's store and material go to a new folder DIR/PRESET/run-TIMESTAMP.
"""

import argparse
import datetime
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path


def run_stage(name, command, capture=False):
    """Runs one stage as its own process; returns its wall and CPU seconds, peak resident memory
    (MB) and, with `capture`, its standard output (printed too)."""
    print(f"== {name}: {' '.join(str(c) for c in command)}", flush=True)
    start = time.monotonic()
    process = subprocess.Popen([str(c) for c in command], stdout=subprocess.PIPE if capture else None, text=True)
    output = process.stdout.read() if capture else ""
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.monotonic() - start
    if capture:
        sys.stdout.write(output)
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(f"paper_scale: {name} failed with exit code {code}")
    return {
        "stage": name,
        "wall_s": wall,
        "cpu_s": usage.ru_utime + usage.ru_stime,
        "peak_mb": usage.ru_maxrss / 1024.0,
        "output": output,
    }


def duration(seconds):
    return f"{seconds:.1f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def number_after(label, text):
    """The first number after `label` in a benchmark's output."""
    match = re.search(re.escape(label) + r"\s*([0-9.]+)", text)
    if not match:
        sys.exit(f"paper_scale: no '{label}' in the benchmark's output")
    return float(match.group(1))


def simulate_once(svbtdf, preset, cache, options=()):
    """The cached simulation, made first when missing (into a temporary folder, renamed when
    complete, so that an interrupted simulation is never taken for a finished one, and resumed
    when a run was interrupted). `options` are
    more `svbtdf simulate` options (the cache folder must then be one for them)."""
    done = cache / "simulated"
    record = cache / "simulated.json"
    if done.is_dir() and record.is_file():
        stage = json.loads(record.read_text())
        stage["stage"] = "simulate (cached)"
        return done, stage
    # An interrupted simulation is resumed (`svbtdf simulate` continues an unfinished folder).
    partial = cache / "simulated.partial"
    cache.mkdir(parents=True, exist_ok=True)
    stage = run_stage("simulate", [svbtdf, "simulate", "--preset", preset, *options, "--out", partial])
    stage.pop("output")
    stage["date"] = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    partial.rename(done)
    record.write_text(json.dumps(stage, indent=2) + "\n")
    return done, stage


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="grid-sheet")
    parser.add_argument("--cache", type=Path, default=Path(os.environ.get("SVBTDF_BENCH_CACHE", Path.home() / ".cache/svbtdf-bench")))
    parser.add_argument("--build", type=Path, default=Path(__file__).resolve().parent.parent / "build")
    parser.add_argument("--threads", type=int, default=0, help="worker threads (0: all cores)")
    args = parser.parse_args()

    svbtdf = args.build / "cli/svbtdf"
    benches = args.build / "bench"
    for tool in (svbtdf, benches / "bench_process", benches / "bench_fit", benches / "bench_refine"):
        if not tool.is_file():
            sys.exit(f"paper_scale: {tool} is missing (cmake --build {args.build} --target svbtdf bench)")
    cache = args.cache / args.preset
    simulated, simulate = simulate_once(svbtdf, args.preset, cache)
    run = cache / ("run-" + datetime.datetime.now().strftime("%Y%m%d-%H%M%S"))
    run.mkdir(parents=True)
    store, material = run / "processed", run / "material"

    process = run_stage("process", [benches / "bench_process", simulated, args.threads, "--keep", store], capture=True)
    process["baseline_s"] = number_after("baseline, read every image once:", process["output"])
    process["wall_s"] = number_after("process:", process["output"])  # the stage's wall less its baseline
    texels = int(number_after("images,", process["output"]))

    # The fit's baseline: the benchmarks' single-thread cost per representative and per refined
    # texel, projected onto this store (1% representatives, every texel refined).
    fit_bench = run_stage("bench_fit", [benches / "bench_fit"], capture=True)
    refine_bench = run_stage("bench_refine", [benches / "bench_refine"], capture=True)
    per_representative = number_after("baseline, fresh workspace, 1 thread:", fit_bench["output"])
    per_texel = number_after("baseline, 1 thread:", refine_bench["output"]) / 1000.0
    # Default options, as a lab runs it (no held-out dots: compare then reports the fit's own).
    fit = run_stage("fit", [svbtdf, "fit", store, "--out", material, "--threads", args.threads])
    fit["baseline_s"] = per_representative * 0.01 * texels + per_texel * texels

    compare = run_stage("compare", [svbtdf, "compare", material, simulated / "truth", "--json", run / "compare.json"],
                        capture=True)
    accuracy = [line for line in compare["output"].splitlines() if line.startswith(("compared", "truth within"))]

    rows = [simulate, process, fit, compare]
    print()
    print(f"{args.preset}: {texels} texels, {os.cpu_count()} cores, "
          f"{datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}")
    print("| stage | wall | CPU | peak memory | baseline | ratio to baseline |")
    print("|---|---|---|---|---|---|")
    for row in rows:
        baseline = row.get("baseline_s")
        against = f"{duration(baseline)} | {row['wall_s'] / baseline:.2f}" if baseline else "- | -"
        print(f"| {row['stage']} | {duration(row['wall_s'])} | {duration(row['cpu_s'])} | {row['peak_mb']:.0f} MB | {against} |")
    print(f"process + fit: {duration(process['wall_s'] + fit['wall_s'])}")
    print("process baseline: reading and decoding every image once, in the same process before it (its CPU "
          "time is in the row's); fit baseline: bench_fit's and bench_refine's single-thread projections for this store")
    for row in rows:
        row.pop("output", None)
    summary = {"preset": args.preset, "texels": texels, "stages": rows, "accuracy": accuracy}
    (run / "paper_scale.json").write_text(json.dumps(summary, indent=2) + "\n")
    print("\n".join(accuracy))
    print(f"written: {run / 'paper_scale.json'}")


if __name__ == "__main__":
    main()
