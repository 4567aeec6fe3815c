#!/usr/bin/env python3
"""Regenerates the settings tables of docs/experiments.md from the schemas (`quijibo settings`).

Usage: scripts/settings-tables.py [--check] [path/to/quijibo]

Each table sits between `<!-- settings: SECTION -->` and `<!-- end settings -->` and is written from
the section's entries: key, type and range, default, and the meaning (the entry's doc, else its
help). With --check nothing is written; the exit code is 1 when a table differs from the schema
(ctest runs this: test settings_tables).
"""
import json
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "experiments.md"
BLOCK = re.compile(r"(<!-- settings: (\S+) -->\n)(.*?)(<!-- end settings -->)", re.S)


def value(v):
    """A default as the tables write it: strings quoted, numbers as JSON writes them."""
    if v is None or v == "":
        return "–"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    if isinstance(v, list):
        return ", ".join(value(x) for x in v)
    return f"`{json.dumps(v)}`" if isinstance(v, str) else json.dumps(v)


def kind(s):
    t = s["type"]
    if t == "choice":
        return ", ".join(f'`"{c}"`' for c in s["choices"])
    if t == "numbers":
        sizes = " or ".join(str(n) for n in s.get("sizes", []))
        return f"{sizes} numbers" + (f" in {s['range']}" if "range" in s else "")
    if "range" in s:
        r = s["range"]
        return f"{t} in {r}" if r[0] in "[(" else f"{t} {r}"
    return t


def table(entries):
    rows = ["| key | type | default | meaning |", "|---|---|---|---|"]
    for s in entries:
        meaning = s.get("doc") or s["help"]
        if len(meaning) > 1 and meaning[0].isupper() and meaning[1].islower():  # a help line, in a row
            meaning = meaning[0].lower() + meaning[1:]
        meaning = meaning.replace("|", "\\|")
        key = s["key"].replace("/", ".")
        rows.append(f"| `{key}` | {kind(s)} | {value(s['default'])} | {meaning} |")
    return "\n".join(rows) + "\n"


def main(argv):
    check = "--check" in argv
    args = [a for a in argv if a != "--check"]
    binary = pathlib.Path(args[0]) if args else ROOT / "build" / "experiments" / "quijibo"
    settings = json.loads(subprocess.run([str(binary), "settings"], check=True, capture_output=True,
                                         text=True).stdout)
    text = DOC.read_text()
    stale = []

    def fill(m):
        new = table(settings[m.group(2)])
        if m.group(3) != new:
            stale.append(m.group(2))
        return m.group(1) + new + m.group(4)

    result = BLOCK.sub(fill, text)
    if not BLOCK.search(text):
        sys.exit(f"{DOC}: no <!-- settings: SECTION --> blocks")
    if check:
        if stale:
            print(f"{DOC}: the tables of {', '.join(stale)} differ from the schemas; "
                  "run scripts/settings-tables.py", file=sys.stderr)
            return 1
        return 0
    DOC.write_text(result)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
