#!/usr/bin/python3
"""Evaluations per second of the Python module's Material.eval against the C++ loop (bench_eval),
in one run on the same material and the same (texel, wi, wo) pairs (docs/benchmarks.md).

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [MATERIAL] [PAIRS] [TEXELS]

MATERIAL defaults to out/demo/material, PAIRS to 1,000,000 spread over TEXELS (default 256)
random texels. Both sides evaluate with every texel's BTDF already built (the first Python call
builds and keeps them; its time is reported apart); the C++ loop runs on one thread, the module
on one thread and on all of them. Prints the rates per second of wall time and per second of CPU
time (on a machine busy with other work only the latter compares the code), and their ratios to
the C++ loop's.
"""

import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

import svbtdf

BUILD = os.path.join(os.path.dirname(os.path.dirname(svbtdf.__file__)), "..")


def cpu_time():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def best_of(repeats, call):
    """The least wall time and the least CPU time (all threads) of `repeats` calls, and a result."""
    best, best_cpu = float("inf"), float("inf")
    for _ in range(repeats):
        start, cpu_start = time.perf_counter(), cpu_time()
        result = call()
        best = min(best, time.perf_counter() - start)
        best_cpu = min(best_cpu, cpu_time() - cpu_start)
    return best, best_cpu, result


def main():
    material_path = sys.argv[1] if len(sys.argv) > 1 else "out/demo/material"
    pairs = int(sys.argv[2]) if len(sys.argv) > 2 else 1_000_000
    texel_count = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    material = svbtdf.Material.load(material_path)
    rng = np.random.default_rng(1)
    chosen = np.stack([rng.integers(0, material.width, texel_count), rng.integers(0, material.height, texel_count)], 1)
    texels = chosen[rng.integers(0, texel_count, pairs)].astype(np.int64)
    wi = rng.normal(size=(pairs, 3))
    wi[:, 2] = -np.abs(wi[:, 2]) - 0.05
    wo = rng.normal(size=(pairs, 3))
    wo[:, 2] = np.abs(wo[:, 2]) + 0.05

    start = time.perf_counter()
    material.eval(texels, wi, wo)
    first = time.perf_counter() - start
    one_thread, one_thread_cpu, values = best_of(3, lambda: material.eval(texels, wi, wo, threads=1))
    all_threads, all_threads_cpu, _ = best_of(3, lambda: material.eval(texels, wi, wo))

    with tempfile.TemporaryDirectory() as folder:
        files = [os.path.join(folder, name) for name in ("texels.i64", "wi.f64", "wo.f64")]
        for array, path in zip((texels, wi, wo), files):
            np.ascontiguousarray(array).tofile(path)
        program = os.environ.get("SVBTDF_BENCH_EVAL", os.path.join(BUILD, "bench", "bench_eval"))
        cpp = json.loads(subprocess.run([program, material_path, *files, "3"], check=True, capture_output=True,
                                        text=True).stdout)
    checksum = float(values.sum())
    assert abs(checksum - cpp["checksum"]) <= 1e-9 * abs(checksum), (checksum, cpp["checksum"])

    cpp_rate, cpp_cpu_rate = cpp["evaluations_per_s"], pairs / cpp["cpu_seconds"]
    print(f"material {material_path}: {material.width} x {material.height} texels; {pairs} pairs over {texel_count} texels")
    print("M evaluations/s                          per second of wall time   per second of CPU time")
    print(f"C++ loop (bench_eval, 1 thread)          {cpp_rate / 1e6:8.3f}                  {cpp_cpu_rate / 1e6:8.3f}")
    rows = [("Material.eval, 1 thread", one_thread, one_thread_cpu),
            (f"Material.eval, all {os.cpu_count()} threads", all_threads, all_threads_cpu)]
    for name, wall, cpu in rows:
        print(f"{name:40s} {pairs / wall / 1e6:8.3f} (ratio {pairs / wall / cpp_rate:4.2f})   "
              f"{pairs / cpu / 1e6:8.3f} (ratio {pairs / cpu / cpp_cpu_rate:4.2f})")
    print(f"first call (builds {texel_count} texels' BTDFs): {first:.2f} s; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
