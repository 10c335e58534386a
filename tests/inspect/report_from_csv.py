#!/usr/bin/python3
"""Recomputes bricklayer-report's numbers from bricklayer-export's CSV files with pandas, reading each
file with a bare pd.read_csv(path) (no options: what "loads in pandas without extra work" means), and
compares them with the report's report.json. An independent second implementation of the report's
definitions (modules/inspect/README.md), in another language, from the CSV alone.

Usage: report_from_csv.py CSV_DIR REPORT_JSON   -> prints what it compared; exit 1 on any difference.
"""
import json
import math
import sys
from pathlib import Path

import pandas as pd

csv_dir, report_path = Path(sys.argv[1]), Path(sys.argv[2])
report = json.loads(report_path.read_text())
index = pd.read_csv(csv_dir / "index.csv")
tables = {row.channel if isinstance(row.channel, str) else "": pd.read_csv(csv_dir / row.file) for row in index.itertuples()}
problems = []
compared = 0


def same(what, mine, theirs):
    global compared
    compared += 1
    if isinstance(mine, float) or isinstance(theirs, float):
        ok = math.isclose(float(mine), float(theirs), rel_tol=1e-9, abs_tol=1e-9)
    else:
        ok = mine == theirs
    if not ok:
        problems.append(f"{what}: {mine!r} from the CSV, {theirs!r} in the report")


def by_type(type_name):
    return [tables[row.channel] for row in index.itertuples() if row.type == type_name]


def messages(df):
    """One row per message: the first row of each log event (per-item files repeat the message)."""
    return df.drop_duplicates("event").sort_values("event")


# Span and per-channel message counts.
all_log_times = pd.concat([t["log_utime_us"] for t in tables.values()])
span_s = (all_log_times.max() - all_log_times.min()) / 1e6
same("span_s", span_s, report["span_s"])
same("events", int(sum(t["event"].nunique() for t in tables.values())), report["events"])
undecoded = tables.get("")
for c in report["channels"]:
    # Every event on the channel: the decoded ones in its file(s), the rest in undecoded.csv.
    n = sum(messages(tables[row.channel]).shape[0] for row in index.itertuples() if row.channel == c["channel"])
    if undecoded is not None:
        n += int((undecoded["channel"] == c["channel"]).sum())
    same(f"messages on {c['channel']}", n, c["messages"])
    same(f"rate of {c['channel']}", n / span_s, c["rate_hz"])

# Rounds: RUNNING (1) from its first message to the first that is not, or a restart of its clock.
rounds, current, last_remaining = [], None, 0
for r in [m for df in by_type("bricklayer.round_t") for m in messages(df).itertuples()]:
    if current and r.state == 1 and r.remaining_ms > last_remaining:
        current["ended"] = "restarted"
        rounds.append(current)
        current = None
    if r.state == 1:
        if not current:
            current = {"start": r.utime_us}
        current.update(end=r.utime_us, max=r.max_score_points, blocks=r.num_blocks)
        last_remaining = r.remaining_ms
    elif current:
        current["end"] = r.utime_us
        if r.state == 2:
            current["max"] = r.max_score_points
        current["ended"] = {2: "time up", 0: "reset"}.get(r.state, f"state {r.state}")
        rounds.append(current)
        current = None
if current:
    current["ended"] = "log ended"
    rounds.append(current)
same("number of rounds", len(rounds), len(report["rounds"]))
for mine, theirs in zip(rounds, report["rounds"]):
    same("round start", int(mine["start"]), theirs["start_utime_us"])
    same("round end", int(mine["end"]), theirs["end_utime_us"])
    same("round MAX", int(mine["max"]), theirs["max_score_points"])
    same("round blocks", int(mine["blocks"]), theirs["num_blocks"])
    same("round ended", mine["ended"], theirs["ended"])
if rounds:
    maxima = sorted(int(r["max"]) for r in rounds)
    same("best MAX", maxima[-1], report["rounds_summary"]["best_max_points"])
    same("median MAX (nearest rank)", maxima[(50 * len(maxima) + 99) // 100 - 1], report["rounds_summary"]["median_max_points"])

# Red episodes: predictions with status OK; red when any block's state is CAUSE (2).
episodes, current = [], None
for df in by_type("bricklayer.prediction_t"):
    df = df[df["status"] == 0]
    red = df.groupby("event")["blocks.state"].apply(lambda s: bool((s == 2).any()))
    first = messages(df).set_index("event")
    for event in first.index:
        p = first.loc[event]
        if red[event] and not current:
            current = {"start": int(p.utime_us), "end": int(p.utime_us), "blocks_red": int(p.num_blocks)}
        elif not red[event] and current:
            current.update(end=int(p.utime_us), blocks_after=int(p.num_blocks), fell=int(p.num_blocks) < current["blocks_red"], open=False)
            episodes.append(current)
            current = None
if current:
    current.update(blocks_after=0, fell=False, open=True)
    episodes.append(current)
same("red episodes", len(episodes), len(report["red_episodes"]))
for mine, theirs in zip(episodes, report["red_episodes"]):
    same("red start", mine["start"], theirs["start_utime_us"])
    same("red duration", mine["end"] - mine["start"], theirs["duration_us"])
    same("red fell", mine["fell"], theirs["fell"])
same("piles that fell", sum(e["fell"] for e in episodes if not e["open"]), report["red_summary"]["fell"])


def nearest_rank(values, p):
    values = sorted(values)
    return int(values[max(1, (p * len(values) + 99) // 100) - 1])


durations = [e["end"] - e["start"] for e in episodes if not e["open"]]
if durations:
    for p in (50, 90, 99):
        same(f"red duration p{p}", nearest_rank(durations, p), report["red_summary"]["duration_us"][f"p{p}"])

# End-to-end latency from the projection's "present" timings, rounded down to 10 us.
timings = pd.concat(by_type("bricklayer.timing_t"))
present = timings[(timings["module"] == "projection") & (timings["stage"] == "present")]
e2e = present["received_utime_us"] + present["elapsed_us"] - present["utime_us"]
e2e = (e2e[e2e >= 0] // 10 * 10).tolist()
same("latency samples", len(e2e), report["latency_us"]["samples"])
for p in (50, 90, 99):
    same(f"latency p{p}", nearest_rank(e2e, p), report["latency_us"][f"p{p}"])
same("latency max", int(max(e2e)), report["latency_us"]["max"])
for st in report["stages_elapsed_us"]:
    v = timings[(timings["module"] == st["module"]) & (timings["stage"] == st["stage"])]["elapsed_us"].tolist()
    same(f"{st['module']}/{st['stage']} samples", len(v), st["samples"])
    same(f"{st['module']}/{st['stage']} p99", nearest_rank(v, 99), st["p99"])

# Modules: heartbeats, restarts (a new instance after the first), errors (per-instance counters).
beats = messages(pd.concat(by_type("bricklayer.heartbeat_t")))
for m in report["modules"]:
    b = beats[beats["module"] == m["module"]].sort_values("event")
    same(f"{m['module']} heartbeats", len(b), m["heartbeats"])
    same(f"{m['module']} restarts seen", b["instance"].nunique() - 1, m["restarts_seen"])
    same(f"{m['module']} launcher restarts", int(b["restarts"].max()), m["launcher_restarts"])
    same(f"{m['module']} errors", int(b.groupby("instance")["errors"].max().sum()), m["errors"])
    same(f"{m['module']} dropped", int(b.groupby("instance")["dropped"].max().sum()), m["dropped"])

# Study sessions (the study module's Table 1): sessions with a known condition, not aborted, both trials
# and three problems answered; the last attempt of each step counts.
if "study" in report:
    names = {1: "blue", 2: "red", 3: "proposed"}
    sessions = messages(pd.concat(by_type("bricklayer.study_session_t"))).sort_values(["session_id", "utime_us"])
    last_state = sessions.groupby("session_id").last()
    trials = messages(pd.concat(by_type("bricklayer.study_trial_t"))).sort_values(["attempt", "utime_us"])
    trials = trials.groupby(["session_id", "trial"]).last()
    answers = messages(pd.concat(by_type("bricklayer.study_answer_t"))).sort_values(["attempt", "utime_us"])
    answers = answers.groupby(["session_id", "problem"]).last()
    same("study sessions", len(last_state), report["study"]["sessions"])
    counted = {}
    for sid, st in last_state.iterrows():
        if st.condition not in names or st.state == 4:
            continue
        if not all((sid, t) in trials.index for t in (1, 2)) or not all((sid, p) in answers.index for p in (1, 2, 3)):
            continue
        counted.setdefault(names[st.condition], []).append(sid)
    rows = {r["condition"]: r for r in report["study"]["rows"]}
    same("study conditions", sorted(counted), sorted(rows))
    for condition, sids in counted.items():
        r = rows.get(condition, {})
        t1 = [trials.loc[(sid, 1)].score_points if "score_points" in trials.columns else trials.loc[(sid, 1)].score for sid in sids]
        t2 = [trials.loc[(sid, 2)].score_points if "score_points" in trials.columns else trials.loc[(sid, 2)].score for sid in sids]
        same(f"{condition} subjects", len(sids), r.get("subjects"))
        same(f"{condition} trial 1 mean", float(sum(t1)) / len(t1), r.get("trial1_mean_points"))
        same(f"{condition} trial 2 mean", float(sum(t2)) / len(t2), r.get("trial2_mean_points"))
        for p in (1, 2, 3):
            outcomes = [answers.loc[(sid, p)].outcome for sid in sids]
            same(f"{condition} problem {p} solved", sum(o in (1, 2) for o in outcomes), r.get("solved", [None] * 3)[p - 1])
            same(f"{condition} problem {p} excess", sum(o == 2 for o in outcomes), r.get("excess", [None] * 3)[p - 1])
        ratios = [b / a for a, b in zip(t1, t2) if a != 0]
        same(f"{condition} ratio mean", sum(ratios) / len(ratios), r.get("ratio_mean"))
        if len(ratios) > 1:
            mean = sum(ratios) / len(ratios)
            same(f"{condition} ratio variance", sum((x - mean) ** 2 for x in ratios) / (len(ratios) - 1), r.get("ratio_variance"))

print(f"{compared} numbers compared, {len(problems)} differ")
for p in problems:
    print("  " + p)
sys.exit(1 if problems else 0)
