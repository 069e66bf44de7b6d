#!/usr/bin/env python3
"""Writes the section "Derivatives (issue 12)" of BENCHMARKS.md from bench/results/derivatives_copies.json
(benches/derivatives.rs through bench/placement.py) and bench/results/pinocchio_derivatives_*.jsonl (both from
bench/derivatives.sh, one session), with each generated function's operation count (`embedyn generate`)."""
import datetime, json, os, platform, re, statistics, subprocess, tempfile

from benchmarks_md import ROOT, last_json, spread, write_section

ROBOTS = [("z1", "models/peers/z1.urdf", False, "pinocchio_derivatives_z1.jsonl"),
          ("anymal_b_floating", "models/peers/anymal_b.urdf", True, "pinocchio_derivatives_anymal.jsonl"),
          ("talos_reduced_floating", "tests/data/erd/talos_reduced.urdf", True, "pinocchio_derivatives_talos.jsonl")]
# Issue 12's speed target is for these two; the others are reported.
TARGETED = {"z1", "anymal_b_floating"}
# GRBDA's robots with constraints (benches/derivatives_large.rs): no peer has these derivatives.
CONSTRAINED = [("mini_cheetah", "tests/data/grbda/mini_cheetah.urdf", "floating base, 12 geared rotors (couplings)"),
               ("mit_humanoid_leg", "tests/data/grbda/mit_humanoid_leg.urdf", "5 geared rotors (couplings)"),
               ("six_bar", "tests/data/grbda/six_bar.urdf", "a closed loop")]
CALLS = [("aba", "aba", "aba", None),
         ("aba_derivatives", "aba_derivatives", "computeABADerivatives", 0.25),
         ("rnea_derivatives", "rnea_derivatives", "computeRNEADerivatives", None)]


def operations(urdf, floating, function):
    """Arithmetic operations of one generated f64 function (binary operators and negations)."""
    with tempfile.TemporaryDirectory() as out:
        args = ["cargo", "run", "-q", "--release", "-p", "embedyn-cli", "--", "generate", urdf, "--only", function,
                "--scalar", "f64", "--out", out] + (["--floating"] if floating else [])
        subprocess.run(args, cwd=ROOT, check=True, capture_output=True)
        text = open(os.path.join(out, "src", "lib.rs")).read()
    body = text[text.index("pub mod f64"):]
    return len(re.findall(r" [-+*/] ", body)) + len(re.findall(r"= -[a-z(]", body))


def main():
    with open(os.path.join(ROOT, "bench", "results", "derivatives_copies.json")) as f:
        runs = json.load(f)
    copies = runs["copies"]
    large_path = os.path.join(ROOT, "bench", "results", "derivatives_large_copies.json")
    if os.path.exists(large_path):
        with open(large_path) as f:
            runs["benches"].update(json.load(f)["benches"])
    lines = [
        "## Derivatives (issue 12)",
        "",
        f"Generated f64 code vs Pinocchio 4.1's analytical derivatives in one session ({datetime.date.today()}, "
        f"{platform.machine()}, `bench/derivatives.sh`), each side from {copies} fresh copies of its binary "
        "(medians, and the range over copies). The generated derivatives are forward-mode dual numbers through "
        "`aba` and `rnea`, traced and folded (docs/conventions.md, \"Derivatives\").",
        "",
        "| robot | call | operations | embedyn generated (ns) | range | Pinocchio (ns) | range | ratio | target |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for robot, urdf, floating, pin_file in ROBOTS:
        pin_path = os.path.join(ROOT, "bench", "results", pin_file)
        if not os.path.exists(pin_path):
            continue
        pin = last_json(pin_path)
        for call, ours_name, theirs_label, target in CALLS:
            xs = runs["benches"].get(f"gen_{ours_name}/{robot}")
            theirs = pin.get(call)
            their_range = pin.get(f"{call}_range")
            if not xs or not theirs:
                continue
            ops = operations(urdf, floating, ours_name)
            ours = statistics.median(xs)
            lines.append(
                f"| {robot} | `{ours_name}` / `{theirs_label}` | {ops:,} | {ours:,.0f} | {spread(xs)} | {theirs:,.0f} | "
                f"{spread(their_range) if their_range else ''} | {ours / theirs:.2f} | {f'≤ {target}' if target and robot in TARGETED else ''} |")
    lines += ["", "Closed loops and couplings (GRBDA's URDF+ files, benches/derivatives_large.rs, same session): "
              "`aba_derivatives_independent`, the derivatives of the independent accelerations along the constraint "
              "manifold, against the same model's generated `aba`; no peer computes these.", "",
              "| robot | what | operations | `aba` (ns) | `aba_derivatives_independent` (ns) | range | × `aba` |",
              "|---|---|---:|---:|---:|---:|---:|"]
    for robot, urdf, what in CONSTRAINED:
        base = runs["benches"].get(f"gen_aba/{robot}")
        xs = runs["benches"].get(f"gen_aba_derivatives_independent/{robot}")
        if not base or not xs:
            continue
        ops = operations(urdf, False, "aba_derivatives_independent")
        a, d = statistics.median(base), statistics.median(xs)
        lines.append(f"| {robot} | {what} | {ops:,} | {a:,.0f} | {d:,.0f} | {spread(xs)} | {d / a:.1f} |")
    lines += ["", "Forward mode costs each direction a pass of the algorithm's tangent arithmetic: on the floating "
              "ANYmal B the 18 directions of q take 19.6k operations of `aba_derivatives`, those of v 20.1k and those "
              "of τ 8.0k (beside the value pass's 4.4k); of `rnea_derivatives` 7.0k, 11.8k and 4.4k (measured by "
              "generating each group alone). That is about Pinocchio's analytical time, not issue 12's 0.25×: the "
              "analytical recursions, the tree's sparsity in ∂τ and M⁻¹, and lanes are the next steps. On the "
              "38-DoF TALOS forward mode loses outright: 256k operations (nv² growth) in one straight-line function "
              "of megabytes, which runs from L2 and memory rather than the instruction cache (0.46 ns per operation "
              "against `aba`'s 0.28), 2.9× Pinocchio's analytical derivatives; there the analytical recursion, "
              "O(nv·depth) instead of O(nv²) tangent work, is not an option but a need.",
              "", "Size (measured 2026-12-02, `embedyn generate`, then `cargo build --release` of the standalone crate): "
              "the floating TALOS reduced (nv = 38) has 256,549 operations in `aba_derivatives` alone, 7.0 MB of "
              "source, 36 s to compile (one core, 0.6 GB), against issue 12's < 20 s; the floating Solo-12's `step` "
              "(the Jacobian of one Euler step) 70,651 operations. Forward mode grows as nv² times the tangent work per "
              "body; fewer operations per direction is the same task as the speed. On 2026-12-03, with the parts in 16 "
              "modules that rustc builds in parallel, on 2 cores: TALOS's `aba_derivatives` in f64 alone 17.1 s wall "
              "(26.7 s of CPU, 0.67 GB), with `rnea_derivatives` 26.3 s (10.5 MB of source, 0.93 GB), both functions "
              "in f64 and f32 99 s (1.6 GB; the machine was shared with a test run then). That last crate used to be "
              "refused before tracing at a predicted 7.1 GB (the size guard now traces what it predicts within four "
              "times the limit).",
              "", "The interpreted derivatives run the same dual numbers untraced, eight directions per pass, with no "
              "zero folded: `aba_derivatives` took 120 µs on the Z1 and 565 µs on the floating ANYmal B (61× and 140× "
              "the interpreted `aba`; measured 2026-12-02 with a loop over one state). They are the oracle and the "
              "way to loop models' manifold derivatives; a control loop calls the generated functions."]
    write_section("\n".join(lines) + "\n")


main()
