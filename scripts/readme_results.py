#!/usr/bin/env python3
"""Copy the headline table of a `sightline bench` report into README.md's Results section.

    python3 scripts/readme_results.py [docs/bench/quick/README.md] [README.md]

Replaces the lines between `<!-- results:begin -->` and `<!-- results:end -->` with the
report's machine line and one table: all methods on the same street cells of SCENE
(section SECTION), so no figure in the README is typed by hand. The whole report, with
every table and plot, stays in docs/bench/.
"""
import os
import re
import sys

SECTION = "## All methods on the same cells"
SCENE = "**lyon1_bdtopo**"
BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def convert(report_path: str) -> str:
    with open(report_path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    machine = next((l for l in lines if l.startswith("Machine:")), None)
    if machine is None:
        raise SystemExit(f"error: {report_path} has no Machine: line")
    try:
        i = next(k for k, l in enumerate(lines) if l.startswith(SECTION))
        j = next(k for k in range(i + 1, len(lines)) if lines[k].startswith(SCENE))
    except StopIteration:
        raise SystemExit(f"error: {report_path} has no {SECTION} table for {SCENE}")
    out = [machine, "", lines[j], ""]
    k = j + 1
    while k < len(lines) and not lines[k].startswith("|"):
        k += 1
    while k < len(lines) and lines[k].startswith("|"):
        out.append(lines[k])
        k += 1
    return "\n".join(out)


def main() -> int:
    report = sys.argv[1] if len(sys.argv) > 1 else "docs/bench/quick/README.md"
    readme = sys.argv[2] if len(sys.argv) > 2 else "README.md"
    with open(readme, encoding="utf-8") as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        print(f"error: {readme} has no {BEGIN} ... {END} markers", file=sys.stderr)
        return 2
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    body = convert(report)
    new = f"{head}{BEGIN}\n{body}\n{END}{tail}"
    tmp = readme + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(new)
    os.replace(tmp, readme)
    return 0


if __name__ == "__main__":
    sys.exit(main())
