"""What the benchmark scripts share."""
import csv
import os


def write_rows(path, rows, fields=None):
    """Write dict rows as CSV (the columns of the first row unless given) and say where."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields or list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"written: {path}")
