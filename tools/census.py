#!/usr/bin/env python3
"""Load census of example-robot-data: every URDF the package ships, loaded by Pinocchio and by embedyn.

For each file it records whether Pinocchio's `buildModelFromUrdf` (no meshes, no root joint added) loads
it, whether `embedyn info FILE` loads it, whether the two agree on nq and nv (Pinocchio counts a
continuous joint as 2 entries of q, embedyn as one angle: nq is compared after that change of layout),
and the first line of embedyn's error when it refuses. Writes a Markdown table (docs/census.md by
default) and prints a summary.

Needs the PyPI packages `example-robot-data` (6.0.0) and `pin` (Pinocchio 4.1), and a built embedyn:
    pip install example-robot-data==6.0.0 pin==4.1.0
    cargo build --release -p embedyn-cli --bin embedyn
    python3 tools/census.py [--embedyn target/release/embedyn] [--out docs/census.md]

Original to this project. Licence: MIT OR Apache-2.0.
"""

import argparse
import importlib.metadata
import json
import os
import subprocess
import sys
import time

sys.dont_write_bytecode = True
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Expected refusals (docs/model-format.md): the file, and a phrase embedyn's error must contain.
EXPECTED_REFUSALS = {
    "romeo_description/urdf/romeo.urdf": "no inertia about its axis",
    "romeo_description/urdf/romeo_laas_small.urdf": "no inertia about its axis",
    "alex_description/urdf/alex_psyonic_hands.urdf": "does not exist",
}


def robots_dir():
    """The `robots/` folder the example-robot-data wheel installs (it ships data, no Python module)."""
    dist = importlib.metadata.distribution("example-robot-data")
    for f in dist.files:
        parts = str(f).replace("\\", "/").split("/")
        if "robots" in parts and parts[-1].endswith(".urdf"):
            path = str(dist.locate_file(f))
            return path[: path.rindex("/robots/") + len("/robots")], dist.version
    raise SystemExit("example-robot-data ships no URDF: is the package installed?")


def pinocchio_load(path):
    import pinocchio as pin

    # urdfdom prints its own complaints on the process's stderr: keep them out of the census output.
    saved = os.dup(2)
    with open(os.devnull, "w") as devnull:
        os.dup2(devnull.fileno(), 2)
        try:
            model = pin.buildModelFromUrdf(path)
        except Exception as e:  # noqa: BLE001 - any failure is a refusal to record
            text = str(e).strip()
            return {"ok": False, "error": text.splitlines()[0] if text else repr(e)}
        finally:
            os.dup2(saved, 2)
            os.close(saved)
    # embedyn's q keeps one angle per continuous joint where Pinocchio keeps (cos, sin).
    continuous = sum(1 for j in model.joints if j.shortname().startswith("JointModelRUB"))
    return {"ok": True, "nq": model.nq - continuous, "nv": model.nv}


def embedyn_load(binary, path):
    start = time.perf_counter()
    run = subprocess.run([binary, "info", path], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    warnings = [l for l in run.stderr.splitlines() if l.startswith("warning:")]
    if run.returncode != 0:
        errors = [l for l in run.stderr.splitlines() if not l.startswith("warning:")]
        return {"ok": False, "error": errors[0] if errors else f"exit {run.returncode}",
                "warnings": warnings, "seconds": seconds, "exit": run.returncode}
    info = json.loads(run.stdout)
    return {"ok": True, "nq": info["nq"], "nv": info["nv"], "warnings": warnings, "seconds": seconds}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--embedyn", default=os.path.join(REPO, "target", "release", "embedyn"),
                    help="the embedyn binary (default: target/release/embedyn)")
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "census.md"))
    args = ap.parse_args()
    import pinocchio as pin

    robots, erd_version = robots_dir()
    files = []
    for root, _, names in os.walk(robots):
        files += [os.path.join(root, n) for n in names if n.endswith(".urdf")]
    files.sort()
    rows = []
    for path in files:
        rel = os.path.relpath(path, robots)
        p = pinocchio_load(path)
        e = embedyn_load(args.embedyn, path)
        agree = "—"
        if p["ok"] and e["ok"]:
            agree = "yes" if (p["nq"], p["nv"]) == (e["nq"], e["nv"]) else \
                f"no (Pinocchio {p['nq']}/{p['nv']}, embedyn {e['nq']}/{e['nv']})"
        reason = ""
        if not e["ok"]:
            # Drop the install prefix from the path in the message.
            reason = e["error"].replace(robots + "/", "")
        elif e["warnings"]:
            reason = f"loads with {len(e['warnings'])} warning(s): " + \
                "; ".join(w.replace(robots + "/", "") for w in e["warnings"][:2])
            if len(e["warnings"]) > 2:
                reason += "; …"
        rows.append((rel, p, e, agree, reason))

    pin_ok = [r for r in rows if r[1]["ok"]]
    both = [r for r in pin_ok if r[2]["ok"]]
    refused = [r for r in pin_ok if not r[2]["ok"]]
    unexpected = [r for r in refused if r[0] not in EXPECTED_REFUSALS
                  or EXPECTED_REFUSALS[r[0]] not in r[4]]
    mismatched = [r for r in both if r[3] != "yes"]
    crashed = [r for r in rows if not r[2]["ok"] and r[2].get("exit", 1) >= 100]

    esc = lambda s: s.replace("|", "\\|")  # noqa: E731
    lines = [
        "# Load census: example-robot-data",
        "",
        f"Every URDF shipped by example-robot-data {erd_version} (PyPI), loaded with Pinocchio "
        f"{pin.__version__} (`pin.buildModelFromUrdf(path)`, no meshes, no root joint added) and with "
        "`embedyn info FILE` (no options). nq is compared in embedyn's layout (one angle per continuous "
        "joint). Written by `tools/census.py`; rerun it after changing the loader.",
        "",
        f"- files: {len(rows)}; Pinocchio loads {len(pin_ok)}; embedyn loads {len(both)} of those "
        f"and refuses {len(refused)} ({', '.join(os.path.basename(r[0]) for r in refused) or 'none'}); "
        f"nq/nv disagree on {len(mismatched)}; refusals not expected by docs/model-format.md: {len(unexpected)}; "
        f"crashes: {len(crashed)}.",
        f"- embedyn load time per file: at most {max(r[2]['seconds'] for r in rows):.2f} s.",
        "",
        "| model | Pinocchio loads? | embedyn loads? | nq/nv agree? | reason if refused (or warnings) |",
        "|---|---|---|---|---|",
    ]
    for rel, p, e, agree, reason in rows:
        pin_cell = "yes" if p["ok"] else "no: " + esc(p["error"].replace(robots + "/", ""))
        lines.append(f"| `{rel}` | {pin_cell} | {'yes' if e['ok'] else 'no'} | {agree} | {esc(reason)} |")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines[4:6]))
    for r in unexpected:
        print(f"UNEXPECTED refusal: {r[0]}: {r[4]}")
    for r in mismatched:
        print(f"MISMATCH: {r[0]}: {r[3]}")
    sys.exit(1 if unexpected or mismatched or crashed else 0)


if __name__ == "__main__":
    main()
