"""The long hostile-user fuzz run (issue 34): the suite's generator
(``tests/fuzz_inputs.py``, through ``tests/e2e/test_fuzz_inputs.py``) with fresh
random seeds, for as many inputs as asked, in chunks, on several lanes.

    python benchmarks/fuzz_long.py --inputs 100000 --lanes 2 --out fuzz-out

Each chunk is one pytest run of the test with ``HTN_FUZZ_INPUTS=CHUNK`` and
``HTN_FUZZ_RANDOM=1``; its tally (inputs per kind, command and exit code)
is appended to ``OUT/tally.jsonl``, its whole output kept in
``OUT/chunk-LANE-N.txt`` when it failed. The summary at the end: inputs per
kind and per exit code, failed chunks (each one's first failing input), and
the time taken. Exit code 1 when any chunk failed.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inputs", type=int, default=100_000, help="inputs in all")
    ap.add_argument("--chunk", type=int, default=2_000, help="inputs per pytest run")
    ap.add_argument("--lanes", type=int, default=2, help="pytest runs at a time")
    ap.add_argument("--out", type=Path, default=Path("fuzz-out"), help="folder for tallies")
    ap.add_argument("--nice", type=int, default=10, help="niceness of the runs")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    tally = args.out / "tally.jsonl"
    chunks = [min(args.chunk, args.inputs - i) for i in range(0, args.inputs, args.chunk)]
    todo = list(enumerate(chunks))
    lock = threading.Lock()
    failed: list = []
    began = time.monotonic()
    done = Counter()

    def lane(number: int) -> None:
        while True:
            with lock:
                if not todo:
                    return
                index, size = todo.pop(0)
            env = {
                **os.environ,
                "HTN_FUZZ_INPUTS": str(size),
                "HTN_FUZZ_RANDOM": "1",
                "HTN_FUZZ_TALLY": str(tally.resolve()),
                "HTN_FUZZ_PLANS": str((args.out / "plans").resolve()),
            }
            r = subprocess.run(
                [
                    "nice",
                    "-n",
                    str(args.nice),
                    sys.executable,
                    "-m",
                    "pytest",
                    "-q",
                    "-s",
                    "-p",
                    "no:cacheprovider",
                    "tests/e2e/test_fuzz_inputs.py",
                ],
                cwd=ROOT,
                env=env,
                capture_output=True,
                text=True,
            )
            with lock:
                done["chunks"] += 1
                done["inputs"] += size
                if r.returncode != 0:
                    path = args.out / f"chunk-{number}-{index}.txt"
                    path.write_text(r.stdout + r.stderr)
                    failed.append(path)
                took = time.monotonic() - began
                rate = done["inputs"] / took
                print(
                    f"{done['chunks']}/{len(chunks)} chunks, {done['inputs']} inputs, "
                    f"{took / 60:.1f} min, {rate:.1f} inputs/s, "
                    f"{'FAILED ' + str(path) if r.returncode else 'ok'}",
                    flush=True,
                )

    threads = [threading.Thread(target=lane, args=(n,)) for n in range(args.lanes)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    summary(tally, failed, time.monotonic() - began)
    return 1 if failed else 0


def summary(tally: Path, failed: list, seconds: float) -> None:
    total: Counter = Counter()
    if tally.is_file():
        for line in tally.read_text().splitlines():
            total.update(json.loads(line))
    inputs = sum(v for k, v in total.items() if k.startswith("exit "))
    print(f"\n{inputs} inputs in {seconds / 60:.1f} min")
    print(
        "per exit code: "
        + ", ".join(f"{k[5:]}: {v}" for k, v in sorted(total.items()) if k.startswith("exit "))
    )
    kinds = sorted({k.split(" exit ")[0][5:] for k in total if k.startswith("kind ")})
    print("per kind:")
    for kind in kinds:
        codes = ", ".join(
            f"exit {k.rsplit(' ', 1)[1]}: {v}"
            for k, v in sorted(total.items())
            if k.startswith(f"kind {kind} exit ")
        )
        print(f"  {kind}: {total['kind ' + kind]} ({codes})")
    print(
        "per command: "
        + ", ".join(f"{k[8:]}: {v}" for k, v in sorted(total.items()) if k.startswith("command "))
    )
    print(f"failed chunks: {len(failed)}")
    for path in failed:
        text = path.read_text()
        at = text.find("AssertionError")
        print(f"  {path}: {text[at : at + 400] if at >= 0 else text[-400:]}")


if __name__ == "__main__":
    sys.exit(main())
