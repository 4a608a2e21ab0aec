#!/usr/bin/env python3
"""Copy a `sightline bench` report into README.md's Results section.

    python3 scripts/readme_results.py [docs/bench/quick/README.md] [README.md]

Replaces the lines between `<!-- results:begin -->` and `<!-- results:end -->` with the
report's machine line, every table and the plots listed in PLOTS (image paths made
relative to the README), so no figure in the README is typed by hand.
"""
import os
import re
import sys

PLOTS = {"fig9-lyon1_bdtopo.png", "table1-time.png", "scaling.png"}
BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def convert(report_path: str, readme_dir: str) -> str:
    rel = os.path.relpath(os.path.dirname(os.path.abspath(report_path)), readme_dir)
    out = []
    with open(report_path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    for line in lines[1:]:  # the report's own title is replaced by the README's heading
        m = re.match(r"!\[(.*)\]\((.*)\)$", line)
        if m:
            if m.group(2) in PLOTS:
                out.append(f"![{m.group(1)}]({rel}/{m.group(2)})")
            continue
        if line.startswith("## "):
            line = "#" + line  # one level down: the README's Results is a `##`
        out.append(line)
    text = "\n".join(out).strip()
    text = re.sub(r"\n{3,}", "\n\n", text)
    return text


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
    body = convert(report, os.path.dirname(os.path.abspath(readme)))
    new = f"{head}{BEGIN}\n{body}\n{END}{tail}"
    tmp = readme + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(new)
    os.replace(tmp, readme)
    return 0


if __name__ == "__main__":
    sys.exit(main())
