#!/usr/bin/env python3
"""Runs every libFuzzer harness of tests/fuzz for a bounded time (scripts/sanitize.sh).

Each harness starts from a copy of its committed corpus (tests/fuzz/corpus/NAME), so that what a
run adds never lands in the repository unasked. Prints one line per harness (executions, rate,
corpus growth, peak memory) and, for a finding, where its input is and how to replay it. Exits 1
if any harness found something."""

import argparse
import concurrent.futures
import pathlib
import re
import shutil
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
CORPORA = ROOT / "tests" / "fuzz" / "corpus"
# Inputs beyond these sizes only slow mutation down; the truth's rig.json is large by nature.
MAX_LEN = {"truth_rig": 262144, "png": 16384, "exr": 32768}
DEFAULT_MAX_LEN = 65536


def stat(output, name):
    match = re.search(rf"stat::{name}:\s*(\d+)", output)
    return int(match.group(1)) if match else 0


def run(build, name, seconds, seed):
    binary = build / "tests" / "fuzz" / f"{name}_fuzzer"
    corpus = build / "fuzz-corpus" / name
    findings = build / "fuzz-findings" / name
    shutil.rmtree(corpus, ignore_errors=True)
    shutil.copytree(CORPORA / name, corpus)
    findings.mkdir(parents=True, exist_ok=True)
    command = [str(binary), str(corpus), f"-max_total_time={seconds}", f"-seed={seed}",
               f"-max_len={MAX_LEN.get(name, DEFAULT_MAX_LEN)}", "-timeout=10",
               "-rss_limit_mb=2048", "-malloc_limit_mb=2048", "-print_final_stats=1",
               f"-artifact_prefix={findings}/", "-close_fd_mask=1"]
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            errors="replace")
    (build / "fuzz-findings" / f"{name}.log").write_text(result.stdout)
    artifacts = sorted(p for p in findings.iterdir() if p.is_file())
    return {
        "name": name,
        "ok": result.returncode == 0 and not artifacts,
        "executions": stat(result.stdout, "number_of_executed_units"),
        "rate": stat(result.stdout, "average_exec_per_sec"),
        "new": stat(result.stdout, "new_units_added"),
        "rss_mb": stat(result.stdout, "peak_rss_mb"),
        "artifacts": artifacts,
        "binary": binary,
        "tail": "\n".join(result.stdout.splitlines()[-40:]),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--build", type=pathlib.Path, required=True)
    parser.add_argument("--seconds", type=int, default=60)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    names = sorted(p.name for p in CORPORA.iterdir() if p.is_dir())
    shutil.rmtree(args.build / "fuzz-findings", ignore_errors=True)
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(lambda n: run(args.build, n, args.seconds, args.seed), names))
    print(f"{'harness':<18} {'executions':>11} {'per s':>7} {'new inputs':>10} {'peak MB':>8}  result")
    for r in results:
        print(f"{r['name']:<18} {r['executions']:>11,} {r['rate']:>7,} {r['new']:>10,} {r['rss_mb']:>8,}  "
              f"{'clean' if r['ok'] else 'FINDING'}")
    failed = [r for r in results if not r["ok"]]
    for r in failed:
        print(f"\n== {r['name']}: finding (log: {args.build}/fuzz-findings/{r['name']}.log)\n{r['tail']}")
        for artifact in r["artifacts"]:
            print(f"replay: {r['binary']} {artifact}")
    total = sum(r["executions"] for r in results)
    print(f"{len(results)} harnesses, {total:,} executions in {args.seconds} s each: "
          f"{'no findings' if not failed else f'{len(failed)} with findings'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
