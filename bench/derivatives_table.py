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
    """Arithmetic operations of one generated f64 function (binary operators and negations), counted once: without
    its AVX twin, the same code again in a module of its own (docs/generated-code.md)."""
    with tempfile.TemporaryDirectory() as out:
        args = ["cargo", "run", "-q", "--release", "-p", "embedyn-cli", "--", "generate", urdf, "--only", function,
                "--scalar", "f64", "--avx-twins", "none", "--out", out] + (["--floating"] if floating else [])
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
        "(medians, and the range over copies). The generator traces each derivative function each way it can — "
        "the analytical world-frame recursion, forward-mode dual numbers through `aba` and `rnea`, and for "
        "forward dynamics of a large tree the factors `q̈`, `∂τ`, `M⁻¹` with `−M⁻¹ ∂τ` in a loop — and keeps the "
        "one that runs fewer statements (docs/conventions.md, \"Derivatives\"). *operations*: arithmetic of the "
        "unrolled code; the loop's product adds 2 · nv · (nonzero rows of ∂τ/∂q and ∂τ/∂v): 13.6k on the "
        "ANYmal B, 97.7k on the TALOS.",
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
    lines += ["", "Which way each function takes, and why: on the Z1 (a 6-DoF chain) the recursion unrolled, 11.0k "
              "operations against dual numbers' 16.3k. On the floating ANYmal B dual numbers fold the free flyer's and "
              "each leg's zeros and pair leg with leg (32.1k statements), the recursion unrolled with its product is "
              "40.9k unpaired, the factors 15.1k (paired) plus the loop: factors (6.2–6.4 µs against dual numbers' "
              "8.9 µs). On the TALOS (nv = 38) dual numbers grow as nv² (254k), the recursion as nv · depth: "
              "`rnea_derivatives` 32.6k against 105k, `aba_derivatives` 85.5k factors plus the loop against 187k "
              "unrolled (its 98k-operation product, straight-line, ran at 0.65 ns per operation: 3.5× Pinocchio in "
              "that run). On this CPU (it has AVX) the Z1's and ANYmal B's derivatives and TALOS's `aba` run their AVX "
              "twins (docs/generated-code.md, \"AVX where the CPU has it\": the same bits; TALOS's derivatives, beyond "
              "25,000 statements, have none); measured in one binary against their baseline copies, the Z1's "
              "`aba_derivatives` took 0.78× the time and the ANYmal B's 0.66×. The 0.25× target remains out of "
              "reach: the Z1 would need 0.08 ns per operation of its 11.0k (it runs at 0.2 with AVX); on the "
              "ANYmal B the loop's `M⁻¹ ∂τ` alone took 1.8–1.9 µs of 6.5–6.7 before the twins (the standalone "
              "crate, `aba_derivatives` against `aba_derivatives_factors` in one binary), most of the target's "
              "whole 2.4–3 µs; Pinocchio pays the same product, in a dense matrix product.",
              "", "Size and compile time (2026-12-03, `embedyn generate`, then `cargo build --release` of the standalone "
              "crate on 2 cores, dependencies built): the floating TALOS's `aba_derivatives` and `rnea_derivatives` in "
              "f64, 4.7 MB of source, 14.1 s wall (0.65 GB); in f64 and f32, 9.2 MB, 32.9 s (1.1 GB). Before the "
              "recursion (dual numbers, 16 modules in parallel): 26.3 s and 99 s; before the modules, 36 s for "
              "`aba_derivatives` alone. `step_derivatives` applies the chain rule to the recursion's ∂q̈ (the floating Solo-12's 46.9k "
              "operations, 70.7k by dual numbers).",
              "", "Interpreted (a loop over one state, 2026-12-03, `--release`): `aba_derivatives` by the recursion "
              "5.9 µs on the Z1, 19.9 µs on the floating ANYmal B, 86 µs on the floating TALOS, against dual numbers' "
              "57.6, 274 and 1,468 µs (6×, 9× and 16× the interpreted `aba`, against 61×, 127× and 255×). Dual "
              "numbers remain the way to loop models' derivatives and a second opinion on trees "
              "(`DerivativeMethod::DualNumbers`); the two agree to 1e-12."]
    write_section("\n".join(lines) + "\n")


main()
