"""The command line every cost benchmark shares (``shafts_cost.py``, ``daylight_cost.py``): the render's size and
samples, the CSV and chart paths, ``--update``, ``--chart-only`` and the hidden ``--worker`` (one worker process
per row, ``worker_result.py``)."""
import argparse
import json
import pathlib


def parser(doc, samples, resolution, eevee_resolution, repeats, csv, png):
    """An ArgumentParser with the shared options; a benchmark adds its own (what to measure) to it."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--samples", type=int, default=samples)
    ap.add_argument("--resolution", default="{}x{}".format(*resolution))
    ap.add_argument("--eevee-resolution", default="{}x{}".format(*eevee_resolution))
    ap.add_argument("--repeats", type=int, default=repeats)
    ap.add_argument("--update", action="store_true", help="keep the CSV's rows not run now")
    ap.add_argument("--out", type=pathlib.Path, default=csv)
    ap.add_argument("--chart", type=pathlib.Path, default=png)
    ap.add_argument("--chart-only", action="store_true")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    return ap


def dispatch(args, worker, read_csv, chart, print_table, kept):
    """Run a worker (``--worker``) or redraw the chart (``--chart-only``: this run's CSV if there is one, else the
    committed one, ``kept``) and return the exit code; else parse the sizes in ``args`` and return None (measure)."""
    if args.worker:
        return worker(json.loads(args.worker))
    if args.chart_only:
        rows = read_csv(args.out if args.out.exists() else kept)
        chart(rows, args.chart)
        print_table(rows)
        return 0
    args.resolution = [int(v) for v in args.resolution.lower().split("x")]
    args.eevee_resolution = [int(v) for v in args.eevee_resolution.lower().split("x")]
    return None


def finish(args, rows, chart, print_table):
    """A measurement's end: the chart of ``rows`` (the CSV as written) at ``args.chart``, the table, the paths."""
    chart(rows, args.chart)
    print_table(rows)
    print(f"\nwrote {args.out}, {args.chart}")
    return 0
