#!/usr/bin/env python3
"""Checks that two dcnet-exp output folders hold the same results, byte for byte.

    same_results.py A B

A and B are folders that dcnet-exp wrote for one spec (a results folder, or an OUT
folder with its plots), for example by one process and by the shards of a job array
and `collect`, or by the binaries of two commits. Every file must be in both and hold
the same bytes, except where dcnet-exp records the process that wrote it: wall-clock
times, the thread count, the host, the commit it was built from. Those files are
compared without those fields:

- manifest.json: without git_commit, started_at, finished_at, stage_seconds, threads,
  host and the digests of training.parquet;
- a cached model's record (.cache/models/*.json, .cache/learned/*.json): without the
  seconds and samples per second of each epoch; its seal (.json.sha256), which holds
  the record's digest, without that digest (the weights, .bin, and their seals are
  compared byte for byte);
- training.parquet and sweep.parquet: without their columns of seconds (needs pyarrow);
- sweep.json: without the digest of sweep.parquet;
- report.md: without its "Run" section and the "training s" column of its DCNet
  training table;
- report.sha256: without the digests of manifest.json and report.md.

Prints what it compared; exits 0 when everything is the same, 1 otherwise.
"""

import json
import sys
from pathlib import Path

WALL_CLOCK_MANIFEST_KEYS = [
    "git_commit",
    "started_at",
    "finished_at",
    "stage_seconds",
    "threads",
    "host",
]
WALL_CLOCK_COLUMNS = ["seconds", "samples_per_s", "training_s"]


def manifest(path):
    document = json.loads(path.read_text())
    for key in WALL_CLOCK_MANIFEST_KEYS:
        document.pop(key, None)
    document.get("files_sha256", {}).pop("training.parquet", None)
    return document


def model_record(path):
    document = json.loads(path.read_text())
    for epoch in document.get("history", []):
        for key in WALL_CLOCK_COLUMNS:
            epoch.pop(key, None)
    return document


def model_seal(path):
    # `<key> <digest of the record>`: the key only.
    return path.read_text().split()[:1]


def sweep(path):
    document = json.loads(path.read_text())
    document.pop("table_sha256", None)
    return document


def table(path):
    import pyarrow.parquet

    table = pyarrow.parquet.read_table(path)
    return table.drop_columns([c for c in WALL_CLOCK_COLUMNS if c in table.column_names])


def report(path):
    kept = []
    section = None
    drop_last_cell = False
    for line in path.read_text().splitlines():
        if line.startswith("## "):
            section = line[3:].strip()
            drop_last_cell = False
        if section == "Run":
            continue
        if section == "DCNet training" and line.startswith("|"):
            cells = line.split("|")
            if cells[-2].strip() == "training s":
                drop_last_cell = True
            if drop_last_cell:
                line = "|".join(cells[:-2] + [""])
        kept.append(line)
    return kept


def digests(path):
    return [
        line
        for line in path.read_text().splitlines()
        if line.split("  ", 1)[-1] not in ("manifest.json", "report.md")
    ]


WITHOUT_WALL_CLOCK = {
    "manifest.json": manifest,
    "training.parquet": table,
    "sweep.parquet": table,
    "sweep.json": sweep,
    "report.md": report,
    "report.sha256": digests,
}


def files(folder):
    return {p.relative_to(folder) for p in folder.rglob("*") if p.is_file()}


def main(a, b):
    a, b = Path(a), Path(b)
    in_a, in_b = files(a), files(b)
    problems = [f"only in {a}: {p}" for p in sorted(in_a - in_b)]
    problems += [f"only in {b}: {p}" for p in sorted(in_b - in_a)]
    identical, without_clock = [], []
    for path in sorted(in_a & in_b):
        if (a / path).read_bytes() == (b / path).read_bytes():
            identical.append(path)
            continue
        compare = WITHOUT_WALL_CLOCK.get(path.name)
        if ".cache" in path.parts and path.name.endswith(".json"):
            compare = model_record
        elif ".cache" in path.parts and path.name.endswith(".json.sha256"):
            compare = model_seal
        if compare is None:
            problems.append(f"differs: {path}")
        elif compare(a / path) == compare(b / path):
            without_clock.append(path)
        else:
            problems.append(f"differs beyond wall-clock fields: {path}")
    print(f"{len(identical)} files byte-identical in {a} and {b}:")
    for path in identical:
        print(f"  = {path}")
    print(f"{len(without_clock)} files the same but for wall-clock times, threads and host:")
    for path in without_clock:
        print(f"  ~ {path}")
    for problem in problems:
        print(f"  ! {problem}")
    if problems or not identical:
        print("the results differ")
        return 1
    print("the results are the same")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
