"""What the scripts that write a section of BENCHMARKS.md share (bench/contact_table.py,
bench/derivatives_table.py): the repository's root, a range of times, the last JSON line of a peer's output,
and replacing one `## ` section of BENCHMARKS.md (or appending it)."""
import json
import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def spread(xs):
    """`min–max` of times in ns, as the tables print a range over binary copies."""
    return f"{min(xs):,.0f}–{max(xs):,.0f}"


def last_json(path):
    """The last JSON object line of a file (bench/placement.py's merged output of a peer)."""
    with open(path) as f:
        return json.loads([line for line in f if line.startswith("{")][-1])


def write_section(section):
    """Replaces the section of BENCHMARKS.md whose `## ` heading is `section`'s first line (up to the next
    `## ` heading), or appends it; prints it."""
    heading = section.split("\n", 1)[0]
    path = os.path.join(ROOT, "BENCHMARKS.md")
    text = open(path).read()
    pattern = re.compile(re.escape(heading) + r"\n.*?(?=\n## |\Z)", re.S)
    body = section.rstrip("\n") + "\n"
    if pattern.search(text):
        text = pattern.sub(lambda _: body, text)
    else:
        text = text.rstrip("\n") + "\n\n" + section
    open(path, "w").write(text)
    print(section)
