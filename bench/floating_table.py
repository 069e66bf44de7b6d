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
        "states; on this CPU, which has AVX, its f64 functions with AVX twins — 4,000 to 25,000 statements, and "
        "smaller ones under a budget per module: here every one of the five functions `embedyn bench` builds (`aba`, `rnea`, `gravity`, `nle`, `crba`) — and "
        "every batch of 24 or more sines and cosines run their AVX copies, the same bits: "
        "docs/generated-code.md, \"AVX where the CPU has it\"), Pinocchio's through `pinocchio_bench --floating` "
        "(g++ -O3, no `-march=native`, as its PyPI wheel is built; compiled with `-mavx` against the wheel's "
        "prebuilt URDF parser it crashes in the model's destructor, Eigen's layouts differing). Issue 13's "
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
                f"{statistics.median(pin):,.0f} | {spread(pin)} | {statistics.median(ratios):.3f} | "
                f"{min(ratios):.3f}–{max(ratios):.3f} | ≤ {target} |"
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
    # Hand-written notes on the runs (kept here so that a rerun keeps them).
    lines += [
        "",
        "2026-12-05, the last run (the table above, seven rounds, commit dcf7639, on a new machine of the same kind: AMD EPYC, 2 vCPUs, AVX-512; the same generated code as the run below). The median ratio of the rounds: G1 `crba` 0.196 (rounds 0.181–0.228, 0.193–0.198 in the five quiet ones), TALOS `crba` 0.196 (0.192–0.250), ANYmal B's 0.124; TALOS `rnea` 0.157 and the G1's `aba` 0.140, each with one slow round (0.266, 0.213). A first run of five rounds half an hour earlier gave G1 `crba` 0.192, TALOS 0.190, and TALOS `rnea` 0.190 (rounds 0.13–0.26). Where the spread comes from: the same runner binary on the same 64 states, started again and again on one vCPU (`taskset`), took ANYmal B's `aba` 344–563 ns, in three levels (about 345, 435 and 500 ns), while Pinocchio's `aba` started between them took 3,743–4,478 ns (at most +18 % against our +60 %). Neither a busy loop nor a memory-bound loop on the other vCPU caused the slow levels reliably (345–457 and 345–500 ns beside them); they come and go with the shared host. The generated code, long and straight, loses more than Pinocchio's loops when the host is busy: compare the rounds, not single runs.",
        "2026-12-05, the run before (five rounds, commit 4a7f0a5): M's structural zeros are written as runs of up to four spread through the body instead of a `memset` before the arithmetic (docs/generated-code.md, \"Structural zeros\"), and a batch of 24 or more sines and cosines is padded with zeros to a multiple of 8 (\"Reading it\"). The median ratio of the rounds: G1 `crba` 0.193 (rounds 0.185–0.194), TALOS 0.195 (0.189–0.203, and one round of 0.289 when the machine was busy), ANYmal B 0.123. The run before it (five rounds, the runs written as slice copies, the same machine code in release): G1 `crba` 0.197 (rounds 0.188–0.206), TALOS 0.195 (0.163–0.197), ANYmal B 0.124; against the same output (Pinocchio's `crba` plus the lower triangle) 0.18. In one binary beside the code of the commit before (the same bits): G1 `crba` 0.965× with the runs alone, the padding a further 0.90× in its AVX-512 twin (0.965× in its AVX twin, 1.02× without AVX); TALOS `crba` 0.90–0.91× (its 32 angles need no padding); the fixed humanoid34's `crba` 0.83×, `rnea` 0.94×, `aba` 0.98×; ANYmal B 0.99–1.01×. The G1's `crba` still moves with where its 27 KB of machine code lands: 489–506 ns in five fresh builds of `embedyn bench` (median 496), and two layouts of one pair of crates gave the new code 413 and 481 ns (the old code 517 and 513).",
        "2026-12-05, the run before (three rounds, the runs alone): G1 `crba` 496 / 2,517 ns (0.20, rounds 0.20–0.20), TALOS 529 / 2,702 (0.20); then with the padding too, three rounds: G1 510 / 2,524 (0.20, rounds 0.20–0.21), TALOS 530 / 2,748 (0.19).",
        "",
        "2026-12-05, the run before those: the twins now call bodies written once (docs/generated-code.md, \"Bodies written once\"), which cut the default crates' compile time (G1 8.7 → 5.8 s, TALOS 8.9 → 6.1 s, bench/compile_time.sh) and left the run time as it was or shortened it: the default crates (f64) of both generators linked into one binary, 11 interleaved rounds, twice: TALOS `crba` 548–550 → 509–510 ns (0.93×), `rnea` 1.00–1.02×, `aba` 1.01×; G1 `crba` 516–519 → 498–507 (0.97–0.98×), `rnea` 0.98×, `aba` 1.00×. The G1's `crba` stays at 0.21–0.22 in the table above (0.20 against the same output), TALOS's at 0.20 (0.19).",
        "2026-12-04, the last two runs (the table above is the second; the first gave TALOS `crba` 562 / 2,770 ns = 0.20 and the G1's 543 / 2,592 = 0.21, both 0.19 against the same output): the humanoids' smallest twinned functions (`kinematics` and `crba` in the default crate; `gravity` and `crba` in the crate `embedyn bench` builds) also get an AVX-512 twin (docs/generated-code.md, \"AVX-512 twins for wide trees\"): 32 vector registers instead of 16, and half the spills (the G1's `crba` twin: 612 instructions touching the stack with AVX, 303 with AVX-512). In one binary with both twins (the AVX one against the AVX-512 one, seven interleaved rounds, twice) the G1's `crba` took 0.89–0.93× the time, TALOS's 0.87–0.91×; in the first run `crba` went from 586 to 562 ns on TALOS (0.21 → 0.20) and from 559 to 543 ns on the G1 (0.22 → 0.21), in the second to 546 and 536 ns (0.20 and 0.21; against Pinocchio's `crba` plus the lower triangle, the same output, 0.19 and 0.20). So the G1's `crba` stays just above issue 13's 0.2. Profiled (perf, the G1's AVX-512 `crba` alone): 81 % in the two parts of the function, 17 % in the `memset` of M (glibc's `rep stosb`, 9.8 KB); replacing it with stores of the 596 structural zeros (64 runs, inlined by LLVM as vector stores) took 499–507 ns against 458–477 with the `memset` in the AVX-512 twin and 550–552 against 577 in the AVX one: the stores, not the `memset` call, are what costs. Nor did the G1's `crba` gain in one part instead of two (a generator with parts of up to 4,000 `let`s, AVX-512 twins of both in one binary: 519 against 459–520 ns; `aba` and `rnea` in fewer parts 0.92–0.98×, but parts that long overflow rustc's stack in debug builds, docs/generated-code.md). Compile time of the default crates: G1 8.1 → 8.7 s, TALOS 8.8 → 8.9 s (bench/compile_time.sh; three interleaved rounds of both generators: G1 7.0–7.3 → 7.8–8.3 s, TALOS 7.2–7.6 → 8.2–8.7 s).",
        "",
        "2026-12-04, the later run: the budget of the smaller functions' AVX twins went from 10,000 to 17,000 statements, so that the humanoids' `rnea` gets its twin beside `kinematics`, `crba` and `aba` in the default crate, and all five functions in the crate `embedyn bench` builds (at 14,000, `nle`, smaller, took `rnea`'s place there: a first rerun at 14,000 left TALOS `rnea` at 0.20 and G1 at 0.19). In one binary with the twins on and off the `rnea` twin took 0.73× the time on TALOS (1,153 → 840 ns) and 0.75× on the G1 (854 → 637); in this run TALOS `rnea` 0.20 → 0.16 and G1 0.19 → 0.17. Compile time of the default crates (three interleaved rounds, 2 cores): G1 6.3–6.6 → 7.1–7.7 s and TALOS 6.8–7.6 → 7.7–7.9 s; in a busier hour 6.8–7.1 → 7.8–8.5 s and 7.5–7.7 → 8.0–8.3 s. `crba` stays above the target: TALOS 0.21 (0.20 against Pinocchio's `crba` plus the lower triangle), G1 0.22 (0.21). Checked and not the cause: the G1 `crba`'s time against the address of `M` (16 offsets over two pages, 553–554 ns at every one); explicit stores of M's 596 structural zeros instead of the memset (merged by LLVM into 158 vector stores; 520–528 against 541–557 ns in one pair of builds, no difference in another: layout noise).",
        "",
        "2026-12-04, the first run of that day with the twin budget: on that host (an AMD EPYC, where every generated function ran slower against Pinocchio than on the Xeon of the day before: in the same script without the change below, ANYmal B `aba`/`rnea`/`crba` 0.13/0.10/0.16, TALOS 0.12/0.28/0.24, G1 0.13/0.19/0.32) the AVX twins paid at every size, so functions below 4,000 statements now get them too under a budget per module (docs/generated-code.md, \"AVX where the CPU has it\": smallest first while the module's twins total at most 10,000 statements). The floating ANYmal B's `aba`, `rnea` and `crba` and the humanoids' `kinematics` and `crba` got twins (from 400 statements: ANYmal B's `kinematics` is smaller) (the humanoids' `rnea` would take TALOS's crate over 10 s of compile time). In one binary with the twins on and off (`dispatch::use_avx`, five interleaved rounds, minimum of 30 batches each, ns): ANYmal B `aba` 515 → 344, `rnea` 213 → 165, `crba` 143 → 114; TALOS `crba` 693 → 555 (and `rnea` 1,002 → 725 with `avx_twins = all`); G1 `crba` 680 → 557 (`rnea` 834 → 632 with `all`); Z1 `aba` 266 → 251, `crba` 97 → 86. The G1's `crba` stayed above the target in that run (0.25; 0.23 against Pinocchio's `crba` plus the lower triangle), TALOS's at 0.21 (0.20). Cutting the G1's twinned `crba` (in one binary, output no longer valid): without its 594 stores of the upper triangle it took 437 ns against 560. The code is bound by its instructions (about 4,000 in the twin, straight-line, beyond the op cache), not by its arithmetic.",
        "",
        "2026-12-04 (the run before this one, on another host): after the fix of the sine/cosine batch (a release-build miscompilation of its quadrant, CHANGELOG; the quadrant now stays a float). In one binary against the code before the fix (three interleaved rounds, ns): floating ANYmal B `crba` 116 → 120, `aba` 310 → 314, `rnea` 165 → 168; G1 with its AVX sine/cosine copy `crba` 377–383 → 377–381, `aba` 768–776 → 785–795, `rnea` 415–427 → 428–433. The first fix, `k as i64`, gave ANYmal B `crba` 113, `rnea` 172 and G1 `crba` 391–395. Against the table of 2026-12-03 (ANYmal B `crba` 109, TALOS 394, G1 386) the rest is this host's drift between runs; the humanoids' `crba` stays at 0.22–0.23 (0.20 against Pinocchio's `crba` plus the lower triangle).",
        "",
        "Body origins on the joint axes (`aba` and `crba` traced on `Model::with_origins_on_joint_axes`, docs/generated-code.md; 2026-12-03, this host, standalone crates of `aba`, `rnea`, `crba` with the default twins built from the commit before and after, one binary each, three interleaved rounds, ns per call): floating ANYmal B `crba` 125–129 → 112–119, `aba` 317–325 → 309–311; TALOS `crba` 404–419 → 392–406 (one round 439), `aba` 794–801 → 775–789; G1 `crba` 379–402 → 377–386, `aba` 807–831 → 768–770; `rnea` unchanged (it stays on the file's frames: traced on moved origins, the G1's ran 1.09× the time with 0.5 % fewer operations, its second part spilling 1,033 times to the stack against 428). `aba_derivatives` (default build): floating ANYmal B 3,644 → 3,540, Z1 1,876 → 1,883. The run of 2026-12-03 after this change had the humanoids' `crba` above 0.2 (G1 0.23, TALOS 0.21; against Pinocchio's `crba` plus the lower triangle 0.21 and 0.19). Tried on the G1's `crba` and counted: all quantities in the root body's frame, Pinocchio's way (dots with world-frame axes instead of a force transform per ancestor): 4,416 statements against 2,953, 1.4× the time.",
    ]
    lines += [
        "",
        "AVX twins against the baseline copies, in one binary (`helpers::dispatch::use_avx` switched between 9 "
        "interleaved rounds, 2026-12-03; the same bits): the floating G1's `aba` 1,030 against 1,854 ns (0.56×; "
        "TALOS's 0.53× in a build with and one without AVX), `rnea` 0.92× and `crba` 0.97× (these two have no twin: "
        "below 4,000 statements; they gained only the sines and cosines' AVX copy; since 2026-12-04 `crba` has "
        "one, above). The baseline copy of the "
        "humanoids' `aba` runs 13.5k instructions of which 5.5k are register copies (SSE2 overwrites an operand); "
        "the AVX copy needs none of them. Before the twins, and before `crba` zeroed M whole instead of storing "
        "its 762 zeros one by one (TALOS: 0.9× the time), the ratios were `aba` 0.24–0.25, `crba` 0.25–0.27 "
        "(2026-12-03, an earlier run on this host).",
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
        "",
        "`crba` in post-order (2026-12-03, runtime/src/algorithms/crba.rs): each body's composite inertia goes to its "
        "parent and its columns are carried up as soon as its subtree is done, instead of every composite first and "
        "every column after. Side by side in one binary (2 runs of 15 interleaved rounds, results equal to 4e-15): the "
        "floating ANYmal B's `crba` 0.84× the time, G1 0.96–0.98×, TALOS 1.04×. Walking the columns before passing "
        "the composite on took ANYmal B 0.81× but halved the pairs of TALOS's arms (its right gripper is turned by π, "
        "and the pairing search, greedy in trace order, probably settled on the wrong signs first).",
        "",
        "The host changes between sessions, and the ratios with it: on the host of the table above (2026-12-03, a "
        "Xeon with AVX-512; every build still targets baseline x86-64), Pinocchio runs 20–25 % faster than on the "
        "host of the day before, the generated code of ANYmal B 40 % faster, that of TALOS and G1 not at all. Their "
        "functions are too large for the instruction cache: TALOS's `crba` is 36.6 KB of machine code (5,927 "
        "instructions in three functions; the L1 instruction cache holds 32 KB), its `rnea` 52 KB and its `aba` 78 KB "
        "(13,357 instructions), against 10.5 KB for ANYmal B's `crba` and 32 KB for its `aba`; each call streams "
        "the code of the humanoids through the decoders again. Per traced operation ANYmal B's `aba` takes 0.15 ns, "
        "TALOS's 0.27 ns. Of TALOS's `crba` "
        "instructions (objdump), 1,034 touch the stack (spills), 1,267 are register copies (SSE2's two-operand "
        "form) and about 1,100 store M, where the arithmetic is 2,200 operations. Measured by cutting the code (in "
        "one binary, output no longer valid): without the 703 stores of the upper triangle it takes 0.84× the time, "
        "with only the diagonal (the composite inertias and the 32 sines and cosines, which alone take about 90 ns) "
        "0.44×. So the columns and their stores cost about half; the 0.2 target for the humanoids' `crba` and `aba` "
        "on this host needs fewer bytes of code per operation (spills, copies, stores), not fewer operations. The AVX twins are that for `aba` (above); `crba`'s twin measured 0.93× the time on that host (TALOS, a build with AVX against one without) and has been given since 2026-12-04 (above).",
    ]
    write_section("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
