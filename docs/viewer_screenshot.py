"""Takes the README's screenshot of ``ndtrace view`` (docs/viewer.png): starts the viewer on a
scene, drags in headless Chromium (Debian's chromium + chromium-driver, selenium) and saves
the window once the full-quality frame is drawn.

    python docs/viewer_screenshot.py [scenes/tesseract.toml] [-o docs/viewer.png] [--set composite.opacity=0.3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", default="scenes/tesseract.toml")
    ap.add_argument("-o", "--output", default=os.path.join(ROOT, "docs", "viewer.png"))
    ap.add_argument("--width", type=int, default=1200, help="viewport width in CSS pixels")
    ap.add_argument("--height", type=int, default=820, help="viewport height")
    ap.add_argument("--drag", type=int, default=14, help="drag steps of (9, 5) pixels before the shot")
    ap.add_argument("--set", action="append", default=[], help="passed to ndtrace view")
    a = ap.parse_args()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains

    sets = [f"--set={s}" for s in a.set]
    server = subprocess.Popen([sys.executable, "-m", "ndtrace", "view", a.scene, "--port", "0", "--no-browser", *sets],
                              cwd=ROOT, stdout=subprocess.PIPE, text=True)
    url = server.stdout.readline().strip()
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)
    try:
        driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                               {"width": a.width, "height": a.height, "deviceScaleFactor": 1, "mobile": False})
        driver.get(url)

        def wait(script: str, timeout: float = 60.0):
            end = time.monotonic() + timeout
            while not driver.execute_script(script):
                if time.monotonic() > end:
                    raise TimeoutError(script)
                time.sleep(0.05)

        wait("return window.ndtraceViewer && window.ndtraceViewer.frames > 0")
        canvas = driver.find_element("css selector", "canvas")
        chain = ActionChains(driver, duration=0).move_to_element(canvas).click_and_hold()
        for _ in range(a.drag):
            chain = chain.pause(0.03).move_by_offset(9, 5)
        chain.release().perform()
        time.sleep(0.5)
        wait("const v = window.ndtraceViewer; return v.acked === v.sent && v.quality === 'full'")
        time.sleep(1.2)  # the status line's frames/s settles
        driver.save_screenshot(a.output)
        print(f"wrote {a.output}")
    finally:
        driver.quit()
        server.send_signal(signal.SIGINT)
        server.wait(15)


if __name__ == "__main__":
    main()
