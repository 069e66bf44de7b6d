#!/usr/bin/env python3
"""Writes the section "Compile time against model size" of BENCHMARKS.md from bench/results/compile_time.jsonl
(bench/compile_time.sh, one session)."""
import datetime, json, os, platform

from benchmarks_md import ROOT, write_section


def main():
    with open(os.path.join(ROOT, "bench", "results", "compile_time.jsonl")) as f:
        rows = [json.loads(line) for line in f if line.startswith("{")]
    lines = [
        "## Compile time against model size (issue 13)",
        "",
        f"The standalone crate of `embedyn generate MODEL [--floating]` with the default functions (`kinematics`, "
        f"`aba`, `rnea`, `crba`, each in f64 and f32), built with `cargo build --release` after its dependency "
        f"(libm) was built: the time is the generated code's alone ({datetime.date.today()}, {platform.machine()}, "
        f"{os.cpu_count()} cores, `bench/compile_time.sh`; wall and user seconds and rustc's peak memory from GNU "
        "time). Issue 13's target: g1_29dof and talos_reduced (floating) under 10 s. The parts of long "
        "functions sit in up to 16 modules per function, which rustc optimizes in parallel "
        "(docs/generated-code.md); before that (2026-12-02) g1_29dof took 9.6 s and talos_reduced 8.4 s. "
        "Since 2026-12-04 functions below 4,000 statements get AVX twins under a budget per module "
        "(docs/generated-code.md, \"AVX where the CPU has it\"): `aba`, `rnea` and `crba` of z1 and the "
        "quadrupeds, and since the budget's rise from 10,000 to 17,000 statements (later that day) all four of "
        "the humanoids' (`rnea` 0.73–0.75× the time). Before, on the host of 2026-12-03: z1 0.8 s, anymal_b "
        "2.0, go2 2.0, solo12 1.9, g1_29dof 8.2, talos_reduced 8.3; on this host with the budget of 10,000 "
        "(humanoids without the `rnea` twin): z1 0.9, anymal_b 2.3, go2 2.3, solo12 2.0, g1_29dof 6.8, "
        "talos_reduced 7.5; with the budget of 17,000 but before the humanoids' `kinematics` and `crba` got "
        "their AVX-512 twins (\"AVX-512 twins for wide trees\"): g1_29dof 8.1, talos_reduced 8.8; with them, "
        "before the twins shared their bodies with the baseline code (2026-12-05, docs/generated-code.md, "
        "\"Bodies written once\"): z1 0.8, anymal_b 2.3, go2 2.2, solo12 2.2, g1_29dof 8.7, talos_reduced 8.9 "
        "(3.1 MB of source each).",
        "",
        "| model | nv | source (KB) | KB per DoF | wall (s) | user (s) | s per DoF (wall) | rustc peak (MB) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in sorted(rows, key=lambda r: r["nv"]):
        kb = r["source_bytes"] / 1024
        lines.append(f"| {r['model']} | {r['nv']} | {kb:,.0f} | {kb / r['nv']:,.1f} | {r['wall_s']:.1f} | "
                     f"{r['user_s']:.1f} | {r['wall_s'] / r['nv']:.2f} | {r['rustc_peak_mb']:,} |")
    write_section("\n".join(lines) + "\n")


main()
