#!/usr/bin/python3
"""End-to-end test of the run report (docs/guides/report.md) in a real headless browser: on a small
synthetic pyramid, `reconstruct` (sweep and refinement) writes report.html; Chromium loads it
with no script error and every image decoded, its screenshot is not blank, the page names no
network resource, and it holds the accuracy table of the synth dataset and a valid check-mesh
verdict for every mesh. `manisweep report` rewrites it with other options, and a folder that is
no run ends with exit 2 and one line naming summary.json. Exit 0 when all hold.
"""
import argparse
import os
import re
import shutil
import sys

from small_pyramid import fresh_small_pyramid, run


def browser():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def browser_check(chrome, page, workdir):
    """The page's own record of what it loaded (data-report-check on <html>)."""
    r = run([chrome, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=10000",
             f"--user-data-dir={workdir}/chrome", "--dump-dom", "file://" + os.path.abspath(page)])
    match = re.search(r'data-report-check="([^"]*)"', r.stdout)
    if not match:
        return None
    return dict(item.split("=") for item in match.group(1).split())


def screenshot_is_not_blank(chrome, page, workdir):
    shot = os.path.join(workdir, "screenshot.png")
    run([chrome, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
         f"--user-data-dir={workdir}/chrome", "--window-size=1400,2000", f"--screenshot={shot}",
         "file://" + os.path.abspath(page)])
    if not os.path.exists(shot):
        return False, "no screenshot written"
    from PIL import Image, ImageStat  # Debian's python3-pil
    image = Image.open(shot).convert("RGB")
    colours = len(image.getcolors(maxcolors=1 << 20) or [])
    spread = max(ImageStat.Stat(image).stddev)
    return colours > 200 and spread > 20, f"{colours} colours, channel spread {spread:.1f}"


def report(ok, what):
    print(("ok  " if ok else "FAIL"), what)
    return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    ms = args.manisweep
    chrome = browser()
    if chrome is None:
        print("FAIL no Chromium found (chromium, chromium-browser, google-chrome): "
              "deploy/setup.sh installs Debian's chromium; this test needs a real browser")
        return 1
    data = fresh_small_pyramid(ms, args.workdir)
    if data is None:
        return 1
    out = os.path.join(args.workdir, "run")
    r = run([ms, "reconstruct", "-i", os.path.join(data, "scene.h5"), "-o", out, "--workers", "2",
             "--max-iterations", "3", "--refine.iterations", "4", "--refine.levels", "2"])
    page = os.path.join(out, "report.html")
    ok = report(r.returncode == 0 and os.path.exists(page),
                f"reconstruct writes report.html (exit {r.returncode})")
    if not ok:
        print(r.stderr[-3000:])
        return 1
    html = open(page, encoding="utf-8").read()
    ok &= report(len(html) < 20e6, f"the page weighs {len(html) / 1e6:.2f} MB (< 20)")
    external = re.findall(r'(?:src|href)="(?!data:|#)[^"]*"', html) + re.findall(r"https?://", html)
    ok &= report(not external, f"no network resource named {external[:3]}")
    for needed in ("Accuracy against the ground truth", "Refinement energy", "Points per iteration",
                   "photo-consistent"):
        ok &= report(needed in html, f"the page holds '{needed}'")
    valid = len(re.findall(r"<td>valid: closed 2-manifold", html))
    ok &= report(valid == 3, f"check-mesh valid for the initial, swept and refined meshes ({valid})")
    check = browser_check(chrome, page, args.workdir)
    ok &= report(check is not None and check["undecoded"] == "0" and check["errors"] == "0" and
                 check["images"] == "13",
                 f"Chromium loads it: {check} (3 views x photograph + 3 meshes, and the error "
                 "figure = 13 images)")
    good, how = screenshot_is_not_blank(chrome, page, args.workdir)
    ok &= report(good, f"the screenshot is not blank: {how}")

    other = os.path.join(args.workdir, "plain.html")
    r = run([ms, "report", out, "-o", other, "--report.cameras", "0",
             "--report.consistency=false"])
    plain = open(other, encoding="utf-8").read() if os.path.exists(other) else ""
    ok &= report(r.returncode == 0 and "<img " not in plain and "not measured" in plain,
                 f"`manisweep report` with no pictures and no photo-consistency (exit {r.returncode})")
    check = browser_check(chrome, other, args.workdir) if plain else None
    ok &= report(check is not None and check["errors"] == "0", f"... loads too: {check}")

    r = run([ms, "report", data])
    lines = [l for l in r.stderr.strip().splitlines() if l.strip()]
    ok &= report(r.returncode == 2 and len(lines) == 1 and "summary.json" in lines[0],
                 f"a folder that is no run: exit {r.returncode}, {lines}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
