#!/usr/bin/python3
"""Markdown summary of a wicp_sweep_* results.csv.

    /usr/bin/python3 scripts/summarize_sweep.py DIR/results.csv
        [--max-rotation-error 2] [--max-translation-error 0.1] [--max-iterations N]

Table 1, per strategy: runs, median fitness score, median rotation and
translation error, and four rates:
  converged  PCL's flag (the CSV's `converged`). PCL also sets it when the
             iteration limit is reached, so it is nearly always 100 %.
  settled    the last stage stopped before the iteration limit (N, by default
             max_iterations from run.json beside the CSV), i.e. PCL's
             relative-MSE criterion ended it.
  best       fitness score within 1 % of the lowest score of the whole sweep:
             the run reached the best optimum found for this map pair. A basin
             measure for base and for --refine runs; weighted runs without
             refinement stop at biased points, with higher scores.
  correct    rotation and translation error within the thresholds of the
             truth ("–" when the truth is unknown).
Table 2, per swept value and strategy: median rotation error (median fitness
score when the truth is unknown) and best runs / runs.
"""

import argparse
import statistics
import sys

from plot_sweep import STRATEGIES, group_of, load_results, run_info

BEST_TOLERANCE = 0.01  # relative, on the fitness score


def fmt(value, digits=3):
    return "–" if value is None else f"{value:.{digits}g}"


def median(values):
    return statistics.median(values) if values else None


def percent(part, whole):
    return f"{100.0 * part / whole:.0f} %" if whole else "–"


def summarize(csv_path, max_rotation_error, max_translation_error, max_iterations):
    sweep, rows = load_results(csv_path)
    max_iterations = max_iterations or run_info(csv_path).get("max_iterations")
    if max_iterations is None:
        raise ValueError(f"{csv_path}: no run.json beside it to take the iteration limit from; give --max-iterations")
    truth_known = all(r["rotation_error_deg"] and r["translation_error_m"] for r in rows)
    strategies = [s for s in STRATEGIES if any(r["strategy"] == s for r in rows)]
    lowest_score = min(float(r["fitness_score"]) for r in rows)

    def best(r):
        return float(r["fitness_score"]) <= lowest_score * (1 + BEST_TOLERANCE)

    def correct(r):
        return (float(r["rotation_error_deg"]) <= max_rotation_error and
                float(r["translation_error_m"]) <= max_translation_error)

    def settled(r):
        refined = int(r["refine_iterations"]) > 0
        return int(r["refine_iterations" if refined else "iterations"]) < max_iterations

    def column_median(selected, column):
        return median([float(r[column]) for r in selected if r[column]])

    lines = ["| strategy | runs | median fitness score | median rotation error (deg) | "
             "median translation error (m) | converged (PCL) | settled | best | correct |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s in strategies:
        mine = [r for r in rows if r["strategy"] == s]
        lines.append(
            f"| {s} | {len(mine)} | {fmt(column_median(mine, 'fitness_score'))} | "
            f"{fmt(column_median(mine, 'rotation_error_deg'))} | {fmt(column_median(mine, 'translation_error_m'))} | "
            f"{percent(sum(r['converged'] == '1' for r in mine), len(mine))} | "
            f"{percent(sum(settled(r) for r in mine), len(mine))} | "
            f"{percent(sum(best(r) for r in mine), len(mine))} | "
            f"{percent(sum(correct(r) for r in mine), len(mine)) if truth_known else '–'} |")

    metric = "rotation_error_deg" if truth_known else "fitness_score"
    lines += ["", f"Median {'rotation error (deg)' if truth_known else 'fitness score'} and best runs / runs "
                  f"(best: score <= {lowest_score:.4g} + {100 * BEST_TOLERANCE:g} %) by swept value:", "",
              "| " + " | ".join(["value"] + strategies) + " |", "|---" * (len(strategies) + 1) + "|"]
    for key, label in sorted({group_of(sweep, r) for r in rows}):
        cells = []
        for s in strategies:
            mine = [r for r in rows if r["strategy"] == s and group_of(sweep, r)[0] == key]
            cells.append(f"{fmt(column_median(mine, metric), 2)} ({sum(best(r) for r in mine)}/{len(mine)})"
                         if mine else "–")
        lines.append("| " + " | ".join([label] + cells) + " |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv", help="results.csv of a wicp_sweep_* tool")
    parser.add_argument("--max-rotation-error", type=float, default=2.0, help="deg, for 'correct' (default 2)")
    parser.add_argument("--max-translation-error", type=float, default=0.1, help="m, for 'correct' (default 0.1)")
    parser.add_argument("--max-iterations", type=int,
                        help="the sweep's --max-iterations, for 'settled' (default: from run.json beside the CSV)")
    args = parser.parse_args()
    try:
        print(summarize(args.csv, args.max_rotation_error, args.max_translation_error, args.max_iterations))
    except ValueError as e:
        print(f"summarize_sweep.py: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
