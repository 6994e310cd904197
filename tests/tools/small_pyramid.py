"""What the command-line tests here share: the small downward pyramid they reconstruct (6 views
of 320 x 240), made in a fresh work folder."""
import argparse
import os
import shutil
import signal
import subprocess


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kw)


def parse_test_arguments(description):
    """The arguments every such test takes: the binary, the Open3D verdict script, a work
    folder."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--verdict", required=True, help="tests/tools/open3d_verdict.py")
    parser.add_argument("--workdir", required=True)
    return parser.parse_args()


def fresh_small_pyramid(manisweep, workdir):
    """Empties `workdir` and synthesises WORKDIR/pyramid; returns that folder, or None after
    printing the failure."""
    shutil.rmtree(workdir, ignore_errors=True)
    os.makedirs(workdir)
    data = os.path.join(workdir, "pyramid")
    r = run([manisweep, "synth", "pyramid-down", "--output", data, "--views", "6", "--width",
             "320", "--height", "240"])
    if r.returncode != 0:
        print("FAIL synth:", r.stderr[-2000:])
        return None
    return data


def interrupt_after(cmd, marker, timeout=300):
    """Runs cmd, sends it SIGINT (Ctrl-C) once its log shows `marker`; returns its exit code."""
    p = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    for line in p.stderr:
        if marker in line:
            p.send_signal(signal.SIGINT)
            break
    p.stderr.read()
    return p.wait(timeout=timeout)
