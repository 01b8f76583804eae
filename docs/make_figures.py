"""Regenerate the figures under docs/img from a campaign made as the README shows (the SDOF
frame on Berkeley's table, random 0-25 Hz at 0.1 and 0.25 in and El Centro, 3 kip of
actuator friction hidden, 1 % sensor noise), diagnosed with the full catalog:

    python docs/make_figures.py

It writes the report's Bode plot and time histories as PNG, then the diagnosis's HTML
report and .rrd, and screenshots both as a lab engineer sees them: the report in headless
Chromium, the .rrd in Rerun's web viewer (`rerun --serve-web`) in headless Chromium with
its software rasterizer, driven by Playwright. The screenshots need Debian's `chromium`
(`apt-get install chromium`) and `pip install playwright` (its own browser download is not
needed); without them the PNG figures are still written and the screenshots are skipped
with a line saying so.

The campaign is cached as benchmarks/bench_readme_campaigns.py caches it."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from readme_campaigns import campaign  # noqa: E402

from vtable import verbs  # noqa: E402
from vtable.viz.diagnosis_report import tf_overlay, time_histories, write_report  # noqa: E402
from vtable.viz.diagnosis_rerun import log_diagnosis  # noqa: E402

#: Chromium headless as root on a machine with no network beyond loopback and no GPU
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--hide-scrollbars"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def screenshot(chromium: str, url: str, png: Path, size: tuple[int, int],
               least_s: float = 2.0, most_s: float = 240.0) -> None:
    """Load `url` in headless Chromium (driven by Playwright) and save the window once it
    has stopped changing: two screenshots 5 s apart alike, after at least `least_s` (a
    canvas app such as Rerun's viewer has no page text to wait for)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=CHROMIUM_FLAGS)
        page = browser.new_page(viewport={"width": size[0], "height": size[1]})
        page.goto(url)
        page.wait_for_timeout(least_s * 1000)
        shot, waited = page.screenshot(), least_s
        while waited < most_s:
            page.wait_for_timeout(5000)
            waited += 5.0
            again = page.screenshot()
            if again == shot:
                break
            shot = again
        png.write_bytes(shot)
        browser.close()


def screenshot_rrd(chromium: str, rrd: Path, png: Path) -> None:
    """Serve `rrd` with Rerun's web viewer on free loopback ports and screenshot it once
    the recording's views are drawn."""
    web, grpc = free_port(), free_port()
    server = subprocess.Popen(["rerun", "--serve-web", "--web-viewer-port", str(web),
                               "--port", str(grpc), str(rrd)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):  # until the web server answers
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", web)) == 0:
                    break
            time.sleep(0.1)
        url = (f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}"
               "%2Fproxy")
        screenshot(chromium, url, png, (1800, 1100), least_s=20.0)
    finally:
        server.terminate()
        server.wait(timeout=10)


def main() -> None:
    root = Path(os.environ.get("VTABLE_README_CACHE",
                               Path.home() / ".cache" / "vtable-readme-campaigns"))
    d = verbs.diagnose(campaign("actuator_friction", 0.01, root))
    out = HERE / "img"
    out.mkdir(exist_ok=True)
    tf_overlay(d, "structure acceleration", d.runs[2]).savefig(out / "report_bode.png", dpi=90)
    time_histories(d, d.runs[2]).savefig(out / "report_time_histories.png", dpi=90)
    print(f"wrote {out / 'report_bode.png'}, {out / 'report_time_histories.png'}")
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    try:
        import playwright  # noqa: F401
    except ImportError:
        chromium = None
    if chromium is None:
        print("no chromium or playwright here: the screenshots are not made "
              "(apt-get install chromium; pip install playwright)")
        return
    with tempfile.TemporaryDirectory() as tmp:
        report = write_report(d, Path(tmp) / "diagnosis.html").resolve()
        rrd = log_diagnosis(d, Path(tmp) / "diagnosis.rrd")
        for anchor in ("tf", "time"):
            png = out / f"screenshot_report_{anchor}.png"
            screenshot(chromium, f"{report.as_uri()}#{anchor}", png, (1100, 1500))
            print(f"wrote {png}")
        png = out / "screenshot_rerun.png"
        screenshot_rrd(chromium, rrd, png)
        print(f"wrote {png}")


if __name__ == "__main__":
    main()
