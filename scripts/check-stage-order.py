#!/usr/bin/env python3
"""Checks the includes of src/flowfusion against docs/design.md's stage order.

A stage folder may include its own headers and those of the folders above it in design.md's
"Stage folders" table, never one below it; no header may take part in an include cycle. Prints
every offence and exits 1, or prints the folders in order and exits 0.
    scripts/check-stage-order.py [REPO_ROOT]
"""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
design = (root / "docs" / "design.md").read_text()
table = design.split("## Stage folders", 1)[1].split("\n## ", 1)[0]
order = re.findall(r"^\| (\w+) \|", table, re.M)
order = [name for name in order if name != "folder"]
rank = {name: i for i, name in enumerate(order)}
src = root / "src" / "flowfusion"
include = re.compile(r'^\s*#\s*include\s+"flowfusion/([^"]+)"', re.M)

problems = []
graph = {}
for path in sorted(src.rglob("*")):
    if path.suffix not in (".h", ".cpp") or path.parent == src:
        continue
    stage = path.relative_to(src).parts[0]
    if stage not in rank:
        problems.append(f"src/flowfusion/{stage}/ is not in docs/design.md's stage table: add its row where it belongs")
        rank[stage] = len(rank)
    name = path.relative_to(src).as_posix()
    graph[name] = include.findall(path.read_text(errors="replace"))
    for target in graph[name]:
        other = target.split("/", 1)[0]
        if other in rank and rank[other] > rank[stage]:
            problems.append(f"src/flowfusion/{name} includes flowfusion/{target}: {other}/ comes after {stage}/ in the stage order")

# Include cycles among the headers (depth-first search, a grey node met again closes a cycle).
state = {}
def visit(node, stack):
    state[node] = "grey"
    stack.append(node)
    for nxt in graph.get(node, []):
        if state.get(nxt) == "grey":
            problems.append("include cycle: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
        elif nxt not in state and nxt in graph:
            visit(nxt, stack)
    stack.pop()
    state[node] = "black"
for node in graph:
    if node not in state:
        visit(node, [])

for p in sorted(set(problems)):
    print(p)
if problems:
    sys.exit(1)
print("stage order (each folder includes only those before it):", " ".join(order))
