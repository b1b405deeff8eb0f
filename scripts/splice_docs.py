#!/usr/bin/env python3
"""Put a generated Markdown block into a docs chapter between its markers.

    scripts/splice_docs.py NAME FILE [SOURCE]

Reads the block from SOURCE (or stdin), drops a leading `# ` title line and the blank lines
after it, and replaces what lies between `<!-- BEGIN NAME -->` and `<!-- END NAME -->` in FILE;
the rest of FILE (its title and prose) is kept. Fails, changing nothing, when FILE lacks the
markers. The table scripts (real_data.sh, injection_table.sh, loss_table.sh, soak.sh) share it.
"""
import re
import sys


def main():
    if len(sys.argv) not in (3, 4):
        raise SystemExit(__doc__.strip().split("\n")[2].strip())
    name, path = sys.argv[1], sys.argv[2]
    src = open(sys.argv[3], encoding="utf-8").read() if len(sys.argv) == 4 else sys.stdin.read()
    lines = src.strip("\n").split("\n")
    if lines and lines[0].startswith("# "):
        lines = lines[1:]
    while lines and not lines[0].strip():
        lines = lines[1:]
    body = "\n".join(lines).rstrip()
    doc = open(path, encoding="utf-8").read()
    pat = re.compile(r"(<!-- BEGIN %s -->\n)(?:.*?\n)?(<!-- END %s -->)" % (re.escape(name), re.escape(name)), re.S)
    if not pat.search(doc):
        raise SystemExit(f"{path} has no markers for {name}")
    doc = pat.sub(lambda m: m.group(1) + body + "\n" + m.group(2), doc)
    open(path, "w", encoding="utf-8").write(doc)
    print(f"{path} ({name}) updated", file=sys.stderr)


if __name__ == "__main__":
    main()
