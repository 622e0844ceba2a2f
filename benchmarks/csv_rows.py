"""A benchmark's result rows (dicts) to CSV, written the same way by every benchmark."""
import csv
import pathlib


def write(path, rows, fields=None, digits=None):
    """Write ``rows`` to ``path`` (its folder made): the columns ``fields`` (default: the first row's
    keys; other keys are left out), floats to ``digits`` significant digits (default: as Python
    prints them)."""
    fields = list(rows[0]) if fields is None else list(fields)
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.{digits}g}" if digits and isinstance(v, float) else v)
                        for k, v in r.items() if k in fields})


def read(path, text_fields=()):
    """The rows of a CSV that ``write`` wrote, as dicts: every value a float where it reads as one, but the
    columns ``text_fields``, which stay strings."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            if k not in text_fields:
                try:
                    r[k] = float(v)
                except (TypeError, ValueError):
                    pass
    return rows
