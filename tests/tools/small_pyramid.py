"""What the command-line tests here share: the small downward pyramid they reconstruct (6 views
of 320 x 240), made in a fresh work folder."""
import os
import shutil
import subprocess


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kw)


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
