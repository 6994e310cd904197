"""What the scalability benchmarks share: running a logged command, a free loopback port, and
writing their figures (OUT/STEM.json with the rows and how they were taken, OUT/STEM.csv with
the rows)."""
import csv
import json
import os
import socket
import subprocess


def run(cmd, log):
    print("+ " + " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def write_figures(out, stem, setup, rows):
    """OUT/STEM.json: `setup` (a dict) and "rows"; OUT/STEM.csv: the rows."""
    with open(os.path.join(out, f"{stem}.json"), "w") as f:
        json.dump({**setup, "rows": rows}, f, indent=1)
    with open(os.path.join(out, f"{stem}.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
