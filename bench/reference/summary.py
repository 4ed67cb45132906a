"""Markdown table of compare.sh's output (read from stdin): per program,
model and thread count the minimum wall and CPU time per vertex-step over
the repeats, the load averages seen, and the library's ratio to groombake."""

import json
import sys

runs = {}
for line in sys.stdin:
    line = line.strip()
    if not line.startswith("{"):
        if line.startswith("droop"):
            print(line)
        continue
    r = json.loads(line)
    if r.get("program") == "pbd":
        key = (f"PositionBasedDynamics {r['model']}", r["iterations"], r["threads"])
    else:
        # With a Newton tolerance the count is a maximum: say what the
        # strands got on average.
        iterations = r["iterations"]
        if r.get("tolerance"):
            iterations = f"at most {iterations} ({r['solves_per_strand_step']:.2f} per strand-step)"
        key = (f"groombake {r['model']}", iterations, r["threads"])
    runs.setdefault(key, []).append(r)

best = {
    key: (
        min(r["ns_per_vertex_step"] for r in rs),
        min(r["cpu_ns_per_vertex_step"] for r in rs),
        min(r["load_average"] for r in rs),
        max(r["load_average"] for r in rs),
        len(rs),
    )
    for key, rs in runs.items()
}
ours = {k[2]: v for k, v in best.items() if k[0].startswith("groombake")}
print()
print("| solver | iterations | threads | runs | ns per vertex-step (wall) | CPU ns per vertex-step "
      "| ratio to groombake (wall / CPU) | load average |")
print("|---|---|---|---|---|---|---|---|")
for (name, iterations, threads), (wall, cpu, lo, hi, n) in sorted(best.items()):
    ratio = ""
    if not name.startswith("groombake") and threads in ours and min(ours[threads][:2]) > 0:
        ratio = f"{wall / ours[threads][0]:.1f}x / {cpu / ours[threads][1]:.1f}x"
    print(f"| {name} | {iterations} | {threads} | {n} | {wall:.1f} | {cpu:.1f} | {ratio} | {lo:.1f}-{hi:.1f} |")
cpus = sorted({r["cpu"] for rs in runs.values() for r in rs if r.get("cpu")})
if cpus:
    print()
    print(f"CPU (groombake's report): {', '.join(cpus)}")
