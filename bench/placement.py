#!/usr/bin/env python3
"""Runs a benchmark binary from several fresh copies of its file and keeps every copy's numbers.

Why: on this machine the same executable, byte for byte, runs the large straight-line generated
functions up to 1.6x slower or faster depending on which copy of the file is executed (measured
2026-12-02: `centroidal` 617-632 ns from five copies of one criterion binary, 1,006 ns from a sixth,
repeatably; the same for Pinocchio's binaries is checked by running them the same way). The virtual
addresses are identical, so it is not the linker's layout: the likely cause is where the file's pages
land in physical memory (caches and TLBs indexed by physical address). One copy is one sample of that
placement; the medians over copies are what the tables report, and the ranges show the spread.

Usage:
  placement.py criterion BINARY COPIES OUT.json [FILTER]
      runs `BINARY --bench [FILTER]` from COPIES copies (criterion's estimates are read after each run)
      and writes {"copies": n, "benches": {id: [median ns per copy]}}
  placement.py command COPIES OUT.jsonl BINARY [ARGS...]
      runs the command from COPIES copies of BINARY; keeps the last JSON line of each run's output and
      writes one line per key: the median over copies (numbers), with "<key>_range": [min, max]
  placement.py pairs COPIES PEER_OUT.jsonl CRITERION_OUT.json CRITERION_BINARY -- PEER_BINARY [ARGS...]
      both of the above, interleaved: a copy of the peer's command, then a copy of the criterion binary,
      COPIES times, so that each pair of runs sees the same state of the shared machine (other tenants
      come and go over minutes). PEER_OUT also keeps each run ("runs", in order): run k of the peer and
      copy k of the criterion binary are a pair, and the tables take the median of the pairs' ratios.
"""
import json
import os
import shutil
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COPY_DIR = os.path.join(ROOT, "target", "bench-copies")


def fresh_copies(binary, n):
    """`n` new files with the binary's bytes (new files: new page-cache pages)."""
    os.makedirs(COPY_DIR, exist_ok=True)
    paths = []
    base = os.path.basename(binary)
    for k in range(n):
        path = os.path.join(COPY_DIR, f"{base}-copy{k}")
        if os.path.exists(path):
            os.remove(path)
        shutil.copyfile(binary, path)
        os.chmod(path, 0o755)
        paths.append(path)
    return paths


def criterion_estimates():
    """{benchmark id: median ns} from target/criterion/**/new/estimates.json."""
    out = {}
    crit = os.path.join(ROOT, "target", "criterion")
    for dirpath, _, files in os.walk(crit):
        if os.path.basename(dirpath) == "new" and "estimates.json" in files:
            with open(os.path.join(dirpath, "benchmark.json")) as f:
                bench_id = json.load(f)["full_id"]
            with open(os.path.join(dirpath, "estimates.json")) as f:
                out[bench_id] = json.load(f)["median"]["point_estimate"]
    return out


def run_criterion(binary, copies, out_path, bench_filter=None):
    runs = {}
    for k, path in enumerate(fresh_copies(binary, copies)):
        print(f"copy {k + 1}/{copies}: --bench {bench_filter or ''}", file=sys.stderr, flush=True)
        run_one_criterion(path, bench_filter, runs)
    with open(out_path, "w") as f:
        json.dump({"copies": copies, "benches": runs}, f, indent=1, sort_keys=True)
        f.write("\n")
    for bench_id, xs in sorted(runs.items()):
        print(f"{bench_id:55s} median {statistics.median(xs):9.1f} ns  range {min(xs):9.1f} - {max(xs):9.1f}",
              file=sys.stderr)


def run_one_command(path, args):
    text = subprocess.run([path] + args, cwd=ROOT, check=True, capture_output=True, text=True).stdout
    lines = [line for line in text.splitlines() if line.startswith("{")]
    return json.loads(lines[-1])


def run_one_criterion(path, bench_filter, runs):
    crit = os.path.join(ROOT, "target", "criterion")
    shutil.rmtree(crit, ignore_errors=True)
    args = [path, "--bench"] + ([bench_filter] if bench_filter else [])
    subprocess.run(args, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    for bench_id, ns in criterion_estimates().items():
        runs.setdefault(bench_id, []).append(ns)


def run_command(copies, out_path, binary, args):
    results = []
    for k, path in enumerate(fresh_copies(binary, copies)):
        print(f"copy {k + 1}/{copies}: {os.path.basename(binary)} {' '.join(args)}", file=sys.stderr, flush=True)
        results.append(run_one_command(path, args))
    write_merged(results, copies, out_path)


def run_pairs(copies, peer_out, crit_out, crit_binary, peer_binary, peer_args):
    results, runs = [], {}
    peers, crits = fresh_copies(peer_binary, copies), fresh_copies(crit_binary, copies)
    for k in range(copies):
        print(f"pair {k + 1}/{copies}: {os.path.basename(peer_binary)} {' '.join(peer_args)}; "
              f"{os.path.basename(crit_binary)} --bench", file=sys.stderr, flush=True)
        results.append(run_one_command(peers[k], peer_args))
        run_one_criterion(crits[k], None, runs)
    write_merged(results, copies, peer_out, keep_runs=True)
    with open(crit_out, "w") as f:
        json.dump({"copies": copies, "benches": runs}, f, indent=1, sort_keys=True)
        f.write("\n")


def write_merged(results, copies, out_path, keep_runs=False):
    merged = dict(results[0])
    for key, value in results[0].items():
        xs = [r.get(key) for r in results]
        # Times are floats; counts and sizes (ints) are the same in every run.
        if isinstance(value, float) and all(isinstance(x, (int, float)) for x in xs):
            merged[key] = statistics.median(xs)
            merged[f"{key}_range"] = [min(xs), max(xs)]
    merged["copies"] = copies
    if keep_runs:
        merged["runs"] = results
    with open(out_path, "w") as f:
        f.write(json.dumps(merged) + "\n")


def main():
    if len(sys.argv) >= 5 and sys.argv[1] == "criterion":
        run_criterion(sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5] if len(sys.argv) > 5 else None)
    elif len(sys.argv) >= 8 and sys.argv[1] == "pairs" and sys.argv[6] == "--":
        run_pairs(int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[7], sys.argv[8:])
    elif len(sys.argv) >= 5 and sys.argv[1] == "command":
        run_command(int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
