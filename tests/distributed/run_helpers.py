"""What the process-level Python tests here share (chaos_test.py, full_disk_test.py,
replay_test.py): their arguments, a fresh work folder, a free loopback port, the small scene's
sweep options, and workers that reconnect fast."""
import argparse
import os
import shutil
import socket
import subprocess

# The small synthetic scene's window and tiles (200 x 150 images).
SWEEP = ["--sweep.tile-size-px", "10", "--sweep.gaussian-sigma-px", "4"]
# Fast failure detection for the coordinator; workers use the same heartbeat.
HEARTBEAT = ["--heartbeat-interval", "0.1", "--liveness", "8"]


def argument_parser(doc):
    """The parser every test here starts from: its docstring, --manisweep and --workdir."""
    parser = argparse.ArgumentParser(description=doc)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--workdir", required=True)
    return parser


def fresh_workdir(work):
    """Empties `work` and returns its processes.log, open for writing."""
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    return open(os.path.join(work, "processes.log"), "w")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def make_scene(ms, work, log):
    """The small downward pyramid (8 views of 200 x 150); returns its scene.h5."""
    subprocess.run([ms, "synth", "pyramid-down", "--views", "8", "--width", "200", "--height",
                    "150", "--output", os.path.join(work, "scene")], check=True, stdout=log,
                   stderr=log)
    return os.path.join(work, "scene", "scene.h5")


def start_worker(ms, port, worker_id, work, log):
    """A worker on one thread that reconnects within half a second and gives up after 60 s."""
    return subprocess.Popen(
        [ms, "worker", "--connect", f"tcp://127.0.0.1:{port}", "--id", worker_id, "--threads", "1"]
        + HEARTBEAT + ["--reconnect-initial", "0.1", "--reconnect-max", "0.5", "--give-up-after",
                       "60", "--cache-dir", os.path.join(work, "cache", worker_id)],
        stdout=log, stderr=log)
