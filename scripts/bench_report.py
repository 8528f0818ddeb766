"""The benchmark's pure parts: figures of runs summarized, bars checked, results compared with a baseline, and
docs/results.md written from one results.json. Nothing here runs semslam or reads the clock (tests:
tests/scripts/benchmark_test.py).

A figure of a case holds, per variant, what the runs measured: `synchronous` (one run at --pacing synchronous,
reproducible), `quiet` and `busy` (runs at the default realtime pacing, the machine otherwise idle or with one
core kept busy), each as {median, min, max, values}. `better` is `lower`, `higher` or null (a count that is
neither: loops, maps); `kind` is `accuracy` (reproducible at synchronous pacing) or `resource` (time, memory:
never reproducible, so never compared at synchronous pacing).
"""

import math
import statistics

VARIANTS = ("synchronous", "quiet", "busy")
REALTIME_VARIANTS = ("quiet", "busy")
# Synchronous figures are bit-reproducible: anything beyond this is a change, not noise.
SYNC_RELATIVE_TOLERANCE = 1e-6
SYNC_ABSOLUTE_TOLERANCE = 1e-9


def _differs(new, old, digits=None):
    """Synchronous: beyond the tolerance above. Realtime (digits given): also by more than half a unit of the
    figure's last printed digit, since runs are not reproducible below that and the page could not show it."""
    tolerance = SYNC_ABSOLUTE_TOLERANCE + SYNC_RELATIVE_TOLERANCE * abs(old)
    if digits is not None:
        tolerance = max(tolerance, 0.5 * 10.0 ** -digits)
    return abs(new - old) > tolerance


def summarize(values):
    """{median, min, max, values} of the numbers given (None values dropped); None when there are none."""
    numbers = [float(v) for v in values if v is not None and not (isinstance(v, float) and math.isnan(v))]
    if not numbers:
        return None
    return {"median": statistics.median(numbers), "min": min(numbers), "max": max(numbers), "values": numbers}


def aggregate(specs, runs):
    """Figures of a case from its runs.

    specs: {figure: spec}, spec as FigureSpec.to_json() gives it (label, unit, better, kind, digits, bars).
    runs: list of (variant, figures dict) for every run that completed.
    Returns {figure: spec + {synchronous, quiet, busy}}.
    """
    out = {}
    for name, spec in specs.items():
        entry = dict(spec)
        for variant in VARIANTS:
            values = [figures.get(name) for v, figures in runs if v == variant]
            values = [v for v in values if v is not None]
            if variant == "synchronous":
                entry[variant] = float(values[0]) if values else None
            else:
                entry[variant] = summarize(values)
        out[name] = entry
    return out


def _values_for(figure, variant, every_run):
    data = figure.get(variant)
    if data is None:
        return None
    if variant == "synchronous":
        return [data]
    return data["values"] if every_run else [data["median"]]


def _holds(op, value, bound):
    if op == "<=":
        return value <= bound
    if op == ">=":
        return value >= bound
    if op == "==":
        return value == bound
    if op == "abs<=":
        return abs(value) <= bound
    raise ValueError("unknown bar operator %r" % op)


def check_bar(figure):
    """True (every condition of the figure's bar holds), False, or None (no bar, or nothing measured for it)."""
    bars = figure.get("bars") or []
    if not bars:
        return None
    verdict, measured = True, False
    for bar in bars:
        values = _values_for(figure, bar["on"], bar.get("every_run", False))
        if values is None:
            continue
        measured = True
        if not all(_holds(bar["op"], v, bar["value"]) for v in values):
            verdict = False
    return verdict if measured else None


def _number(value, digits):
    if value is None:
        return "–"
    if digits == 0:
        return "%d" % round(value)
    return "%.*f" % (digits, value)


def bar_text(figure):
    unit = figure.get("unit") or ""
    parts = []
    for bar in figure.get("bars") or []:
        op = {"<=": "≤", ">=": "≥", "==": "=", "abs<=": "|x| ≤"}[bar["op"]]
        text = "%s %s%s" % (op, _number(bar["value"], figure.get("digits", 3)), (" " + unit) if unit else "")
        qualifiers = [bar["on"]]
        if bar.get("every_run"):
            qualifiers.append("every run")
        parts.append("%s (%s)" % (text, ", ".join(qualifiers)))
    return "; ".join(parts)


def stats_text(stats, digits):
    """'0.135 [0.131–0.142]' (median [range]) or one number for a single run."""
    if stats is None:
        return "–"
    if len(stats["values"]) == 1 or stats["min"] == stats["max"]:
        return _number(stats["median"], digits)
    return "%s [%s–%s]" % (_number(stats["median"], digits), _number(stats["min"], digits),
                           _number(stats["max"], digits))


def compare(baseline, results):
    """Every figure that got worse than the baseline by more than the run-to-run range measured.

    Realtime (quiet, busy): worse when the new median lies outside the baseline's [min, max] widened on each side
    by the new runs' range (max - min), on the figure's worse side; a variant of one run is widened by the widest
    range among the figure's realtime variants. Synchronous: any change of an accuracy figure
    beyond a tiny tolerance is reported (`changed`, with whether it went the better or the worse way).
    A case of the same name run on other inputs (another title) is not compared: kind 'not compared'.
    Returns a list of findings {case, figure, variant, kind ('worse' | 'changed' | 'failed' | 'not compared'),
    baseline, new, text}.
    """
    findings = []
    old_cases = (baseline or {}).get("cases", {})
    for case_name, case in results.get("cases", {}).items():
        old = old_cases.get(case_name)
        if old is None or old.get("status") != "ok":
            continue
        if case.get("status") == "failed":
            findings.append(_case_finding(case_name, "failed", "failed (%s)" % case.get("reason", "")))
            continue
        if old.get("title") and case.get("title") and old["title"] != case["title"]:
            # The same name, other inputs (a --quick town against the full one's): nothing to compare.
            findings.append(_case_finding(case_name, "not compared", "not compared, the baseline ran %s; this run %s"
                                          % (old["title"], case["title"])))
            continue
        if case.get("status") != "ok":
            continue
        for name, figure in case.get("figures", {}).items():
            before = old.get("figures", {}).get(name)
            if before is None:
                continue
            findings.extend(_compare_figure(case_name, name, before, figure))
    return findings


def _case_finding(case_name, kind, text):
    return {"case": case_name, "figure": None, "variant": None, "kind": kind, "baseline": None, "new": None,
            "text": "%s: %s" % (case_name, text)}


def _compare_figure(case_name, name, before, figure):
    findings = []
    better = figure.get("better")
    digits = figure.get("digits", 3)
    unit = figure.get("unit") or ""
    label = "%s %s" % (case_name, name)
    if better in ("lower", "higher"):
        # A variant of one run (the busy one, by default) measures no spread of its own: the widest range of
        # the figure's realtime runs stands for it.
        widths = [figure[v]["max"] - figure[v]["min"] for v in REALTIME_VARIANTS if figure.get(v)]
        for variant in REALTIME_VARIANTS:
            new, old = figure.get(variant), before.get(variant)
            if new is None or old is None:
                continue
            width = new["max"] - new["min"] if len(new["values"]) > 1 else max(widths)
            low, high = old["min"] - width, old["max"] + width
            bound = high if better == "lower" else low
            beyond = new["median"] > bound if better == "lower" else new["median"] < bound
            worse = beyond and _differs(new["median"], bound, digits)
            if worse:
                detail = "median %s %s, outside the baseline's %s–%s widened by this run's range %s" % (
                    _number(new["median"], digits), unit, _number(old["min"], digits), _number(old["max"], digits),
                    _number(width, digits))
                findings.append({
                    "case": case_name, "figure": name, "variant": variant, "kind": "worse",
                    "baseline": old, "new": new, "detail": detail,
                    "text": "%s (%s): %s" % (label, variant, detail)})
    if figure.get("kind") == "accuracy":
        new, old = figure.get("synchronous"), before.get("synchronous")
        if new is not None and old is not None:
            if _differs(new, old):
                way = "changed"
                if better == "lower":
                    way = "worse" if new > old else "better"
                elif better == "higher":
                    way = "worse" if new < old else "better"
                detail = "%s -> %s %s (%s)" % (_number(old, max(digits, 4)), _number(new, max(digits, 4)), unit, way)
                findings.append({
                    "case": case_name, "figure": name, "variant": "synchronous", "kind": "changed",
                    "direction": way, "baseline": old, "new": new, "detail": detail,
                    "text": "%s (synchronous): %s" % (label, detail)})
    return findings


def worse_findings(findings):
    """The findings that say a figure got worse (or a case failed); a synchronous change for the better, or of a
    figure that is neither better nor worse (loops, maps), is not one."""
    return [f for f in findings if f["kind"] in ("worse", "failed") or
            (f["kind"] == "changed" and f.get("direction") == "worse")]


def _joined(findings, per_case):
    """The findings' lines, one per case (per_case: the details after one head naming the case and its variant;
    else each detail after its figure and variant), joined in the order found; a finding without a detail (a
    failed case, or one of older results) keeps its own line."""
    lines, index = [], {}
    for f in findings:
        if "detail" not in f:
            lines.append(f["text"])
            continue
        if per_case:
            key, head = f["case"], "%s (%s): " % (f["case"], f["variant"])
            part = "%s %s" % (f["figure"], f["detail"])
        else:
            key, head = f["case"], "%s: " % f["case"]
            part = "%s %s: %s" % (f["figure"], f["variant"], f["detail"])
        if key in index:
            lines[index[key]] += "; " + part
        else:
            index[key] = len(lines)
            lines.append(head + part)
    return lines


def duration_text(seconds):
    seconds = int(round(seconds))
    if seconds < 60:
        return "%d s" % seconds
    if seconds < 3600:
        return "%d min %02d s" % divmod(seconds, 60)
    hours, rest = divmod(seconds, 3600)
    return "%d h %02d min" % (hours, rest // 60)


GROUP_TITLES = {
    "real": "Real drives (../shared/data)",
    "long": "The long real drive (KITTI 00, frames 0-1699)",
    "synthetic": "Synthetic towns (seeds no test uses)",
    "demo": "The demo",
    "city": "Many drives, one city map",
    "first_output": "The first hour: a fresh clone to the demo's report",
}


def markdown(results, known_limits=""):
    """docs/results.md from one results.json (and the hand-written known limits, included verbatim)."""
    lines = []
    add = lines.append
    commit = results.get("commit", {})
    machine = results.get("machine", {})
    sha = commit.get("short") or commit.get("sha", "?")[:10]
    add("# Measured results")
    add("")
    source = ("one run of `scripts/benchmark.sh`" if not results.get("merged_from") else
              "%d runs of the benchmark with one binary (the commands below)" % results["merged_from"])
    add("Generated by `scripts/benchmark.py --markdown` from %s; do not edit by hand (the known limits at the end "
        "come from `docs/known_limits.md`)." % source)
    add("")
    if results.get("quick"):
        add("> **A quick run** (`--quick`: fewer and shorter cases, fewer runs). The full benchmark "
            "(`scripts/benchmark.sh`) measures every case and is what the bars are judged by.")
        add("")
    add("- Command: `%s`" % results.get("command", "scripts/benchmark.sh"))
    add("- Commit: `%s`%s, %s" % (sha, " (with uncommitted changes)" if commit.get("dirty") else "",
                                  results.get("date", "")))
    if results.get("binary_version"):
        add("- Binary: `%s`" % results["binary_version"])
    took = duration_text(results.get("seconds", 0))
    if results.get("seconds_by_command"):
        took += " (by command: %s)" % ", ".join(duration_text(t) for t in results["seconds_by_command"])
    add("- Machine: %s cores, %s, %s GiB memory; the benchmark took %s" % (
        machine.get("nproc", "?"), machine.get("cpu", "?"), machine.get("memory_gib", "?"), took))
    add("- Each case: once at `--pacing synchronous` (reproducible); at the default realtime pacing %s run(s) on "
        "the quiet machine and %s with one core kept busy, given as median [min–max]." % (
            results.get("runs", "?"), results.get("busy_runs", results.get("runs", "?"))))
    add("- `ATE`: RMSE after Sim(3) alignment (mono) or SE(3) (stereo) against the ground truth, every frame with "
        "a pose of its own.")
    add("")
    comparison = results.get("comparison")
    if comparison is not None and not comparison.get("baseline_commit"):
        add("No baseline yet (`%s` does not exist): nothing compared. `scripts/benchmark.sh --update-baseline` "
            "writes one." % comparison.get("baseline", "bench/baseline.json"))
        add("")
    elif comparison is not None:
        findings = comparison.get("findings", [])
        worse = worse_findings(findings)
        apart = [f for f in findings if f["kind"] == "not compared"]
        others = [f for f in findings if f not in worse and f not in apart]
        add("Against `%s` (commit `%s`): %s." % (
            comparison.get("baseline", "bench/baseline.json"), comparison["baseline_commit"],
            "no figure got worse by more than its measured run-to-run range" if not worse else
            "%d figure(s) worse by more than the measured run-to-run range" % len(worse)))
        for line in _joined(worse, per_case=False):
            add("- %s" % line)
        if others:
            add("")
            add("Changed at synchronous pacing, not for the worse:")
            for line in _joined(others, per_case=True):
                add("- %s" % line)
        if apart:
            add("")
            add("Not compared (other inputs under the same name):")
            for f in apart:
                add("- %s" % f["text"])
        add("")
    cases = results.get("cases", {})
    # A group without a title of its own still gets a section: no case's figures are left out.
    groups = list(GROUP_TITLES) + sorted({c.get("group") for c in cases.values()} - set(GROUP_TITLES), key=str)
    for group in groups:
        members = [(n, c) for n, c in cases.items() if c.get("group") == group]
        if not members:
            continue
        add("## %s" % GROUP_TITLES.get(group, group))
        add("")
        if any(c.get("status") == "ok" for _, c in members):
            add("| case | figure | bar | synchronous | quiet | busy | |")
            add("|---|---|---|---|---|---|---|")
        notes = []
        for name, case in members:
            if case.get("status") != "ok":
                notes.append("- `%s` (%s): **%s**: %s" % (name, case.get("title", ""), case.get("status"),
                                                        case.get("reason", "")))
                continue
            first = True
            for fname, figure in case.get("figures", {}).items():
                digits = figure.get("digits", 3)
                unit = figure.get("unit") or ""
                verdict = check_bar(figure)
                add("| %s | %s%s | %s | %s | %s | %s | %s |" % (
                    ("`%s`" % name) if first else "", figure.get("label", fname), (" (%s)" % unit) if unit else "",
                    bar_text(figure), _number(figure.get("synchronous"), digits),
                    stats_text(figure.get("quiet"), digits), stats_text(figure.get("busy"), digits),
                    {True: "pass", False: "**FAIL**", None: ""}[verdict]))
                first = False
            for failure in case.get("failures", []):
                notes.append("- `%s`: %s" % (name, failure))
        described = [(n, c) for n, c in members if c.get("status") == "ok"]
        if described:
            add("")
            for name, case in described:
                command = case.get("command")
                add("- `%s`: %s.%s" % (name, case.get("title", ""), " `%s`" % command if command else ""))
            add("")
        if notes:
            lines.extend(notes)
            add("")
    if known_limits.strip():
        add(known_limits.strip())
        add("")
    return "\n".join(lines)
