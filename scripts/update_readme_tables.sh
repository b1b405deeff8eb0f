#!/usr/bin/env bash
# Copy the generated tables into README.md between their markers, so README never holds a
# hand-typed result:
#   <!-- BEGIN real_data -->  ... <!-- END real_data -->   from docs/real_data.md (scripts/real_data.sh)
#   <!-- BEGIN detection -->  ... <!-- END detection -->   from docs/diagnose.md (scripts/detection_table.sh)
#   <!-- BEGIN svd -->        ... <!-- END svd -->         from docs/svd.md (scripts/bench_vs_python_control.sh, scripts/svd_scale.sh)
#   <!-- BEGIN loss -->       ... <!-- END loss -->        from docs/loss.md (scripts/loss_table.sh)
#   <!-- BEGIN injection -->  ... <!-- END injection -->   from docs/injection.md (scripts/injection_table.sh)
#   <!-- BEGIN soak -->       ... <!-- END soak -->        from docs/soak.md (scripts/soak.sh, by hand)
# Each source section is the block of Markdown table lines (and the paragraph right above it)
# that the generating script wrote. Run after the generating scripts.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 - <<'PY'
import re

def tables(path, first=None, last=None):
    """All Markdown table blocks of a file, each with the paragraph just above it."""
    lines = open(path, encoding="utf-8").read().split("\n")
    blocks, i = [], 0
    while i < len(lines):
        if lines[i].startswith("|"):
            j = i
            while j < len(lines) and lines[j].startswith("|"):
                j += 1
            k = i - 1
            if k >= 0 and lines[k] == "":
                k -= 1
            para = []
            while k >= 0 and lines[k].strip() and not lines[k].startswith(("|", "#")):
                para.insert(0, lines[k])
                k -= 1
            blocks.append((para + [""] if para else []) + lines[i:j])
            i = j
        else:
            i += 1
    return blocks[first:last]

def splice(readme, name, blocks):
    body = "\n\n".join("\n".join(b) for b in blocks)
    pat = re.compile(r"(<!-- BEGIN %s -->\n)(?:.*?\n)?(<!-- END %s -->)" % (name, name), re.S)
    if not pat.search(readme):
        raise SystemExit(f"README.md has no markers for {name}")
    return pat.sub(lambda m: m.group(1) + body + "\n" + m.group(2), readme)

readme = open("README.md", encoding="utf-8").read()
readme = splice(readme, "real_data", tables("docs/real_data.md"))
readme = splice(readme, "detection", tables("docs/diagnose.md", 1))  # skip the model-field table
readme = splice(readme, "svd", tables("docs/svd.md"))
readme = splice(readme, "loss", tables("docs/loss.md"))
readme = splice(readme, "injection", tables("docs/injection.md"))
readme = splice(readme, "soak", tables("docs/soak.md"))
open("README.md", "w", encoding="utf-8").write(readme)
print("README.md tables updated")
PY
