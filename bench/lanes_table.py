#!/usr/bin/env python3
"""Writes the section "Many states per call (issue 13)" of BENCHMARKS.md from bench/results/lanes_{baseline,native}.json
(benches/lanes.rs through bench/placement.py, two builds) and bench/results/pinocchio_lanes_*.jsonl (Pinocchio 4.1's
single-state calls), all from one session of bench/lanes.sh."""
import datetime, json, os, platform, statistics

from benchmarks_md import ROOT, last_json, write_section

ROBOTS = [("z1", "pinocchio_lanes_z1.jsonl", {"aba": 0.05}),
          ("anymal_b_floating", "pinocchio_lanes_anymal.jsonl", {"aba": 0.08})]
PARALLEL = {"z1": "pinocchio_parallel_z1.jsonl", "anymal_b_floating": "pinocchio_parallel_anymal.jsonl"}
BATCH = 1024
CALLS = ["aba", "rnea", "crba", "aba_derivatives"]
LANES = 4


def load(name):
    with open(os.path.join(ROOT, "bench", "results", name)) as f:
        return json.load(f)


def main():
    builds = [("baseline x86-64, twins (default: AVX-512 on this host)", load("lanes_baseline.json")),
              ("baseline x86-64, AVX twins (`use_avx512(false)`)", load("lanes_avx_twins.json")),
              ("baseline x86-64, SSE2 copies (`use_avx(false)`)", load("lanes_baseline_copies.json")),
              ("`-C target-cpu=native`", load("lanes_native.json"))]
    copies = builds[0][1]["copies"]
    lines = [
        "## Many states per call (issue 13)",
        "",
        f"Generated f64 functions and their lane versions (`lanes = {LANES}`: module `f64x{LANES}`, {LANES} states per "
        f"call, one per SIMD lane, lane by lane bit-identical to the scalar functions) against Pinocchio 4.1's "
        f"single-state calls, in one session ({datetime.date.today()}, {platform.machine()}, `bench/lanes.sh`), each "
        f"binary from {copies} fresh copies (medians). ns per state: a lane call's time divided by {LANES}. Two builds "
        "of the same code: the baseline x86-64 target, as it runs (each lane function of the `f64x4` module has two "
        "twins, chosen at run time: one 256-bit instruction per lane value, compiled with AVX-512 F and VL (32 "
        "registers) where the CPU has them, with AVX elsewhere, docs/generated-code.md; the scalar functions here are "
        "below the size of a scalar twin), again with the AVX twins (`dispatch::use_avx512(false)`, what a CPU "
        "without AVX-512 runs) and with its baseline copies alone (`dispatch::use_avx(false)`: an `F64x4` is two 128-bit SSE2 registers), and "
        "`-C target-cpu=native` (AVX-512 registers on this host; Pinocchio's wheel is built for the baseline).",
        "",
        "| robot | call | build | Pinocchio (ns) | generated (ns) | ratio | lanes (ns per state) | ratio | vs generated | `_batch` of 64 (ns per state) | target |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for robot, pin_file, targets in ROBOTS:
        pin = last_json(os.path.join(ROOT, "bench", "results", pin_file))
        for call in CALLS:
            theirs = pin.get(call)
            for build, runs in builds:
                one = runs["benches"].get(f"gen_{call}/{robot}")
                four = runs["benches"].get(f"gen_{call}_x{LANES}/{robot}")
                if not one or not four or not theirs:
                    continue
                scalar = statistics.median(one)
                per_state = statistics.median(four) / LANES
                target = targets.get(call)
                batch = runs["benches"].get(f"gen_{call}_batch64/{robot}")
                batch_text = f"{statistics.median(batch) / 64:,.0f}" if batch else ""
                lines.append(
                    f"| {robot} | `{call}` | {build} | {theirs:,.0f} | {scalar:,.0f} | {scalar / theirs:.2f} | "
                    f"{per_state:,.0f} | {per_state / theirs:.3f} | {per_state / scalar:.2f} | {batch_text} | "
                    f"{f'≤ {target}' if target else ''} |")
    lines += ["", "2026-12-05, this run (a new machine of the same kind as the day before: AMD EPYC, 2 vCPUs, "
              "AVX-512): the floating ANYmal B's scalar `aba` ran at 506 ns in this binary, against 346 ns in "
              "the floating-bases table of the same hour: one of the slow levels of the shared host (see the "
              "note under \"Floating bases\"); against 346 ns its lanes' 212 ns per state are 0.61×, not 0.42×. "
              "Pinocchio's Z1 `aba` took 1,924 ns, against 1,386 ns on the host of 2026-12-04."]
    lines += ["", "The lanes pay where the scalar code leaves the vector units idle: each operation of the scalar "
              "function becomes one operation on four states. What they do not remove is the scalar code's own cost "
              "per operation (spills of long functions, issue 13's first item), which the lane values, four times "
              "wider, pay four times over in memory traffic. Sines and cosines of f64 lanes run the scalar kernel "
              "on whole SIMD values (in three passes over all the angles, as the scalar batch); f32 lanes take them "
              "lane by lane. The `_batch` forms add the transposition of states into lanes and back. Eight f64 lanes "
              "(two 256-bit values per number) measured 7–9 % slower per state than four (`_batch` of 64 with AVX2, "
              "on an earlier host: z1 140 against 128 ns, ANYmal B 441 against 412 ns): twice the live values, more "
              "spills; they are not offered. `embedyn bench` reports the `_batch` forms of its baseline build as "
              "`generated_f64_batch`. `embedyn eval --engine generated` does not go through the lanes: on 20,000 floating "
              "ANYmal B samples of `aba` it took 0.73 s (2026-12-02), of which the generated `aba` itself is about 20 ms; "
              "the rest is reading and writing JSON and the text exchanged with the runner process (the interpreted "
              "engine, in one process, took 0.21 s), so lanes would save under 3 %.",
              "",
              "The scalar functions of robots with mirrored branches compute both sides in one SSE2 register "
              "(pairs; the floating ANYmal B's here), and in their baseline copies four f64 lanes are slower per "
              "state than the scalar call. So the `_batch` form of a paired function runs the scalar function "
              "state by state where AVX does not run (the `_batch` column of the SSE2 rows; the same bits), and "
              "through the lanes in its AVX twin. Lane twins arrived on 2026-12-03: before, lane modules had "
              "256-bit registers only from `-C target-cpu=native`, and the baseline build ran as its SSE2 rows "
              "do now."]
    lines += ["", "`aba_derivatives` over lanes: the Z1's (11k operations) gets both twins and takes under a sixth of "
              "Pinocchio's `computeABADerivatives` per state, the figure for a multiple-shooting MPC that "
              "differentiates its knots four at a time (issue 12's target of 0.25× is for one state per call). "
              "The floating ANYmal B's lane copy, beyond the 25,000 statements up to which `avx_twins = large` "
              "twins lane functions, has no twin, and in its SSE2 copy four lanes take longer per state than "
              "the scalar function with its AVX twin: batch it with `avx_twins = all` (2.9 µs per state against "
              "4.6 in a trial of the same session, 34 s against 20 s to compile the crate's `f64` and `f64x4` "
              "modules) or with `-C target-cpu=native`, or call the scalar function per state."]
    lines += ["", f"### Threads over a batch", "",
              f"{BATCH} states per call of `aba`, ns per state. Pinocchio: a loop of `aba` over the states, and its "
              "OpenMP `abaInParallel` (one state per thread, a `ModelPool` of one `Data` per thread) with 1 and 2 "
              "threads (bench/peers/pinocchio_parallel.cpp). embedyn: `f64x4::aba_batch` on one thread and "
              "`embedyn::parallel::par_batch` (rayon's pool, pieces of 64 states, each an `aba_batch`) on this "
              f"machine's {os.cpu_count()} cores, both builds.", "",
              "| robot | Pinocchio loop | `abaInParallel` 1 thread | 2 threads | build | `aba_batch` 1 thread | "
              "`par_batch` | speedup of threads | `par_batch` / `abaInParallel` (2 threads) |",
              "|---|---:|---:|---:|---|---:|---:|---:|---:|"]
    for robot, _, _ in ROBOTS:
        path = os.path.join(ROOT, "bench", "results", PARALLEL[robot])
        if not os.path.exists(path):
            continue
        pin = last_json(path)
        for build, runs in builds:
            one = runs["benches"].get(f"gen_aba_batch{BATCH}/{robot}")
            par = runs["benches"].get(f"gen_aba_par{BATCH}/{robot}")
            if not one or not par:
                continue
            one, par = statistics.median(one) / BATCH, statistics.median(par) / BATCH
            lines.append(
                f"| {robot} | {pin['aba_serial']:,.0f} | {pin['aba_parallel_1']:,.0f} | {pin['aba_parallel_2']:,.0f} | "
                f"{build} | {one:,.0f} | {par:,.0f} | {one / par:.2f}× | {par / pin['aba_parallel_2']:.3f} |")
    write_section("\n".join(lines) + "\n")


main()
