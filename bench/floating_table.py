#!/usr/bin/env python3
"""Writes the section "Floating bases (issue 13)" of BENCHMARKS.md from bench/results/floating.jsonl (bench/floating.sh:
each round, Pinocchio's `pinocchio_bench --floating` and `embedyn bench --floating --json` on each model)."""
import datetime, json, os, platform, statistics

from benchmarks_md import ROOT, spread, write_section

CALLS = [("aba", 0.2), ("rnea", 0.2), ("crba", 0.2)]


def main():
    rows = {}
    with open(os.path.join(ROOT, "bench", "results", "floating.jsonl")) as f:
        for line in f:
            r = json.loads(line)
            rows.setdefault(r["model"], []).append(r)
    version = next(iter(rows.values()))[0]["pinocchio"].get("pinocchio", "?")
    lines = [
        "## Floating bases (issue 13)",
        "",
        f"Generated f64 `aba`, `rnea`, `crba` on robots with a free-flyer root against Pinocchio {version} "
        f"(`aba` in its faster WORLD convention), {datetime.date.today()}, {platform.machine()}, `bench/floating.sh`: "
        "the two sides alternate, model by model, for each round; the times are the medians over rounds, the "
        "ranges their spread, the ratio the median of the rounds' ratios. Ours through `embedyn bench --floating "
        "--json` (the generated code built for the baseline x86-64 target and timed in-process on random "
        "states), Pinocchio's through `pinocchio_bench --floating` (g++ -O3, no `-march=native`). Issue 13's "
        "target: every ratio ≤ 0.2. The generated code computes isomorphic branches (legs, arms) side by side "
        "as pairs (docs/generated-code.md, \"Left and right side by side: pairs\"). The machine is shared: "
        "compare the rounds' ratios, and see below for a side-by-side measurement in one binary.",
        "",
        "| model | nv | call | embedyn generated (ns) | range | Pinocchio (ns) | range | ratio | rounds' ratios | target |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for model, runs in rows.items():
        nv = runs[0]["pinocchio"]["nv"]
        for call, target in CALLS:
            ours = [r["embedyn"][call]["generated_f64"] for r in runs]
            pin = [r["pinocchio"][call] for r in runs]
            ratios = [o / p for o, p in zip(ours, pin)]
            lines.append(
                f"| {model} | {nv} | `{call}` | {statistics.median(ours):,.0f} | {spread(ours)} | "
                f"{statistics.median(pin):,.0f} | {spread(pin)} | {statistics.median(ratios):.2f} | "
                f"{min(ratios):.2f}–{max(ratios):.2f} | ≤ {target} |"
            )
    # Pinocchio's crba fills the upper triangle of M only; ours writes all of M (both triangles and the
    # zeros between branches). The same output from Pinocchio costs its crba and the copy of the lower
    # triangle (`crba_full`, timed by pinocchio_bench since 2026-12-03).
    full = [(model, runs) for model, runs in rows.items() if all("crba_full" in r["pinocchio"] for r in runs)]
    if full:
        lines += [
            "",
            "Pinocchio's `crba` fills the upper triangle of M only (its documentation says so; the entries of joints on "
            "different branches are not written either); the generated `crba` writes the whole symmetric M: for TALOS "
            "1,444 entries (762 of them zeros) where Pinocchio writes about 360. The same output from Pinocchio is "
            "its `crba` followed by the copy of the lower triangle (`M.triangularView<StrictlyLower>() = "
            "M.transpose()…`), timed in the same runs:",
            "",
            "| model | embedyn `crba` (ns) | Pinocchio `crba` + lower triangle (ns) | range | ratio | rounds' ratios |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        for model, runs in full:
            ours = [r["embedyn"]["crba"]["generated_f64"] for r in runs]
            pin = [r["pinocchio"]["crba_full"] for r in runs]
            ratios = [o / p for o, p in zip(ours, pin)]
            lines.append(
                f"| {model} | {statistics.median(ours):,.0f} | {statistics.median(pin):,.0f} | {spread(pin)} | "
                f"{statistics.median(ratios):.2f} | {min(ratios):.2f}–{max(ratios):.2f} |"
            )
    lines += [
        "",
        "Side by side in one binary (generated crates of each variant linked together, bit-identical results, 9 interleaved "
        "rounds, 2026-12-02): the floating G1's paired `aba` in parts of 1,000 / 2,000 / 4,000 statements / one "
        "part took 2,077 / 1,900 / 1,800 / 1,669 ns, `rnea` 1,130 / 1,030 / 936 / 922 ns, `crba` 1,173 / 1,118 / "
        "1,043 / 1,057 ns. Paired bodies above 8,000 operations were cut in parts of 1,000 to save compile time; "
        "they are now cut evenly in parts of up to 2,000 (0.91× the time), since the parts' modules compile in "
        "parallel. Larger parts run faster still but overflow rustc's stack when built with debug info (LLVM's "
        "DWARF writer recurses once per `let`).",
        "",
        "Paired functions in trace order against the former longest-chain-first schedule, side by side in one binary "
        "(bit-identical results, medians of 9 interleaved rounds, 3–4 runs each, 2026-12-03): `aba` 0.81–0.84× the "
        "time on TALOS, 0.85× on G1, 0.78–0.83× on ANYmal B; `crba` 0.84×, 0.73×, 0.92–1.00×; `rnea` 0.93–0.96×, "
        "0.93×, 0.95–1.03× (two runs of one binary differ by up to ±10 % on this shared machine). Writing each output "
        "entry in the part that computes it instead of through the scratch arrays took TALOS's `crba` a further "
        "0.92–0.97×.",
    ]
    write_section("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
