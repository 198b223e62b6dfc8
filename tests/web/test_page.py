#!/usr/bin/python3
"""The web page in a real browser (headless Chromium through chromedriver)
against a real cncstreamd with a simulated machine:

  load the page -> upload examples/plaque.stl -> fill the tool-path form ->
  generate -> preview -> start on the sim -> progress reaches 100 % ->
  a step jog moves the DRO by the step -> a press-and-hold jog moves while
  held (past the daemon's 0.3 s lease, so the page renews it) and stops when
  released -> a hold released by the window losing focus -> the page at a
  390x844 phone viewport shows the DRO and the jog pad without horizontal
  scrolling -> with a token required, the page works from #token=... and
  from the prompt.

Screenshots are kept in the output folder (the test's artefacts).
Exit codes: 0 passed, 1 failed, 77 skipped (no Chromium on this machine).

  test_page.py --daemon build/release/cncstreamd --source . --output build/release/test-output/web
  test_page.py --mock ...   (develop against tests/web/mock_daemon.py instead)
"""
import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import traceback
import urllib.request

SKIP = 77
# CNCSTREAM_CHROMIUM names another browser binary (or a missing one, to check the skip).
CHROMIUM = next((p for p in ([os.environ["CNCSTREAM_CHROMIUM"]] if os.environ.get("CNCSTREAM_CHROMIUM") else
                             ["/usr/bin/chromium", "/usr/bin/chromium-browser"]) if os.path.exists(p)), None)
CHROMEDRIVER = shutil.which("chromedriver") or ("/usr/bin/chromedriver" if os.path.exists("/usr/bin/chromedriver") else None)
if not CHROMIUM or not CHROMEDRIVER:
    print("SKIP: Chromium or chromedriver is not installed (scripts/setup.sh installs chromium chromium-driver)")
    sys.exit(SKIP)
# Chromium is here, so selenium must be too (the same setup installs both):
# a missing module is a failure, not a skip.
from selenium import webdriver  # noqa: E402
from selenium.common.exceptions import TimeoutException  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.support.ui import Select, WebDriverWait  # noqa: E402

T0 = time.monotonic()


def say(msg):
    print(f"[{time.monotonic() - T0:6.1f} s] {msg}", flush=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def end_process(proc, sig=15):
    """Asks a child to end (SIGTERM; PostgreSQL's fast shutdown is SIGINT), killed after 10 s."""
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


class Daemon:
    """The daemon under test on a free loopback port with a fresh data folder."""

    def __init__(self, args, out, name, require_token=False, machines=None):
        self.data = tempfile.mkdtemp(prefix="cncstream-web-")
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}/"
        self.log_path = os.path.join(out, f"{name}.log")
        self.log = open(self.log_path, "w")
        web = os.path.join(args.source, "web")
        if args.mock:
            cmd = [sys.executable, os.path.join(args.source, "tests", "web", "mock_daemon.py"),
                   "--port", str(self.port), "--web", web, "--machines", "sim,bench"]
            if require_token:
                self.token = "mocktoken"
                cmd += ["--token", self.token]
        else:
            cfg = os.path.join(self.data, "cncstreamd.toml")
            with open(cfg, "w") as f:
                f.write(f'listen = "127.0.0.1:{self.port}"\n'
                        # The journal defaults into data_dir: never the user's, and no jobs from an earlier run.
                        f'data_dir = {json.dumps(os.path.join(self.data, "state"))}\n'
                        # sim: as fast as it goes, for the job; bench: real time, so
                        # a held jog moves for as long as it is held (the dead man matters).
                        + (machines or
                           '[[machine]]\nname = "sim"\nport = "sim"\nsim_speed = "max"\n'
                           '[[machine]]\nname = "bench"\nport = "sim"\nsim_speed = "1"\n') +
                        f'[security]\nrequire_token = {"true" if require_token else "false"}\n'
                        f'[web]\nroot = {json.dumps(web)}\n')
            cmd = [args.daemon, "--config", cfg]
        say(f"starting {' '.join(cmd)}")
        self.proc = subprocess.Popen(cmd, stdout=self.log, stderr=subprocess.STDOUT)
        try:
            self._wait_ready(args, require_token)
        except BaseException:
            self.stop()  # the caller gets no object to stop: leave no daemon behind
            raise

    def _wait_ready(self, args, require_token):
        deadline = time.monotonic() + 30
        while True:
            if self.proc.poll() is not None:
                with open(self.log_path) as f:
                    raise AssertionError(f"the daemon exited with {self.proc.returncode}; its log:\n{f.read()}")
            try:
                with urllib.request.urlopen(self.url + "api/v1/health", timeout=2) as r:
                    if json.load(r).get("ok"):
                        break
            except OSError:
                pass
            if time.monotonic() > deadline:
                raise AssertionError("the daemon did not answer /api/v1/health within 30 s")
            time.sleep(0.1)  # polling a process that has no readiness signal
        if require_token and not args.mock:
            # The daemon writes its token at first start (docs/api-v1.md).
            with open(os.path.join(self.data, "state", "token")) as f:
                self.token = f.read().strip()

    def stop(self):
        end_process(self.proc)
        self.log.close()
        shutil.rmtree(self.data, ignore_errors=True)


def browser():
    o = webdriver.ChromeOptions()
    o.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1400,1000", "--hide-scrollbars", "--force-device-scale-factor=1"):
        o.add_argument(a)
    o.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    d = webdriver.Chrome(service=Service(CHROMEDRIVER), options=o)
    d.set_page_load_timeout(30)
    return d


class Page:
    def __init__(self, d, out):
        self.d = d
        self.out = out
        self.shots = []

    def q(self, css):
        return self.d.find_element(By.CSS_SELECTOR, css)

    def click(self, target):
        """Clicks like a user: scrolled to the middle of the screen first, so the
        sticky header never covers it."""
        e = self.q(target) if isinstance(target, str) else target
        self.d.execute_script("arguments[0].scrollIntoView({block: 'center'})", e)
        e.click()

    def text(self, css):
        return self.q(css).text.strip()

    def wait(self, what, fn, timeout=20):
        """Waits for fn() to be truthy; the failure names what was awaited."""
        try:
            return WebDriverWait(self.d, timeout, poll_frequency=0.05).until(lambda _: fn())
        except TimeoutException:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}") from None

    def shot(self, name):
        path = os.path.join(self.out, name + ".png")
        self.d.save_screenshot(path)
        self.shots.append(path)
        say(f"screenshot {path}")

    def full_shot(self, name):
        """The whole page, not only the viewport (Chrome DevTools)."""
        import base64
        self.d.execute_script("window.scrollTo(0, 0)")  # else the sticky header is drawn where the view was
        m = self.d.execute_cdp_cmd("Page.getLayoutMetrics", {})
        w, h = m["cssContentSize"]["width"], m["cssContentSize"]["height"]
        r = self.d.execute_cdp_cmd("Page.captureScreenshot", {"format": "png", "captureBeyondViewport": True,
                                                              "clip": {"x": 0, "y": 0, "width": w, "height": h, "scale": 1}})
        path = os.path.join(self.out, name + ".png")
        with open(path, "wb") as f:
            f.write(base64.b64decode(r["data"]))
        self.shots.append(path)
        say(f"screenshot {path}")

    def keep_failure(self, name):
        """A failed flow's screenshot, page source and browser console, kept in the output folder."""
        try:
            self.shot("FAILED-" + name)
            with open(os.path.join(self.out, f"FAILED-{name}.html"), "w") as f:
                f.write(self.d.page_source)
            for e in self.console_errors():
                say(f"browser console: {e}")
        except Exception:  # the browser itself may be what failed
            pass

    def dro(self, axis):
        t = self.text(f"#dro-{axis}")
        return float(t) if t not in ("", "—") else None

    def state(self):
        return self.q("#state").get_attribute("data-state")

    def status_seq(self):
        return self.d.execute_script(
            "const r = window.cncstream.state.machines.get(window.cncstream.state.current);"
            "return r && r.status ? (r.status.seq ?? null) : null;")

    def connected(self):
        return self.q("#link").get_attribute("data-up") == "1" and self.dro("x") is not None and self.state() == "idle"

    def console_errors(self):
        try:
            return [e for e in self.d.get_log("browser") if e["level"] == "SEVERE"]
        except Exception:  # not every driver keeps the log
            return []


def drop_text_file(d, name, text):
    """Drops a text file on the page's drop zone, as a file dragged from the desktop."""
    d.execute_script("""
        const dt = new DataTransfer();
        dt.items.add(new File([arguments[1]], arguments[0], {type: 'text/plain'}));
        const z = document.getElementById('drop');
        for (const t of ['dragenter', 'dragover', 'drop'])
          z.dispatchEvent(new DragEvent(t, {dataTransfer: dt, bubbles: true, cancelable: true}));""", name, text)


def wait_stopped(p, axis):
    """The machine is idle and the DRO holds still over several status reports."""
    p.wait("the state to return to Idle", lambda: p.state() == "idle", 15)
    v = p.dro(axis)
    seq = p.status_seq()
    p.wait("three more status reports", lambda: (p.status_seq() or 0) >= (seq or 0) + 3, 10)
    assert abs(p.dro(axis) - v) < 0.0005, f"{axis} still moving after release: {v} -> {p.dro(axis)}"
    return p.dro(axis)


def main_flow(args, out, d):
    daemon = Daemon(args, out, "daemon")
    p = Page(d, out)
    try:
        # ---- load
        d.get(daemon.url)
        p.wait("the page to connect and show an idle machine with a DRO", p.connected, 30)
        p.shot("01-loaded")
        say(f"loaded: state {p.text('#state')}, X {p.dro('x')} Y {p.dro('y')} Z {p.dro('z')}")

        # ---- upload through the file chooser
        part = os.path.join(args.source, "examples", "plaque.stl")
        p.q("#file-input").send_keys(part)
        p.wait("the tool-path form for plaque.stl", lambda: p.q("#toolpath-form").is_displayed() and p.text("#tp-part") == "plaque.stl", 60)
        assert "STL" in p.text("#upload-status") and "34,908 facets" in p.text("#upload-status").replace("\u202f", ","), p.text("#upload-status")

        # ---- the tool-path form: a coarse stepover and step keep the job short (the
        # deadlines below are generous for a sanitizer build; a pass ends each wait at once)
        def fill(css, v):
            e = p.q(css)
            e.clear()
            e.send_keys(str(v))
        Select(p.q("#tp-cutter")).select_by_value("ball")
        fill("#tp-diameter", 6)
        fill("#tp-stepover", 2)
        Select(p.q("#tp-direction")).select_by_value("y")
        fill("#tp-feed", 2500)
        fill("#tp-plunge", 500)
        fill("#tp-rpm", 12000)
        fill("#tp-step", 1)
        # Rows only, from the part's top: the page sends the complete job's
        # fields (the daemon's own tests cut the roughing and the waterlines).
        Select(p.q("#tp-strategy")).select_by_value("raster")
        fill("#tp-stock", "none")
        p.shot("02-form")
        p.click("#tp-generate")

        # ---- generated: in the queue as ready, with its preview drawn
        ready = "#queue li[data-state=ready]"
        p.wait("the job to be generated (ready in the queue)", lambda: d.find_elements(By.CSS_SELECTOR, ready), 240)
        job_id = d.execute_script(f"return document.querySelector('{ready}').dataset.job")
        meta = d.execute_script(f"return document.querySelector('{ready} .meta').textContent")
        assert "ball:6" in meta and "stepover 2 mm" in meta and "along Y only" in meta and "stock none" in meta, meta
        p.wait("the preview of the job", lambda: p.q("#preview").is_displayed() and p.q("#preview").get_attribute("data-job") == job_id, 30)
        # The preview must have drawn something: count coloured (height map) pixels.
        coloured = d.execute_script("""
            const c = document.getElementById('preview-canvas'), x = c.getContext('2d');
            const d = x.getImageData(0, 0, c.width, c.height).data; let n = 0;
            for (let i = 0; i < d.length; i += 4) if (d[i] + d[i+1] + d[i+2] > 120) n++;
            return n / (c.width * c.height);""")
        assert coloured > 0.2, f"the preview is mostly empty ({coloured:.0%} coloured)"
        # Drawn from the daemon's picture and thinned path, not from the whole program.
        natural = d.execute_script("const i = document.getElementById('preview-img'); return [i.complete, i.naturalWidth, i.naturalHeight];")
        assert natural[0] and natural[1] > 0 and natural[2] > 0, f"the preview picture did not load: {natural}"
        fetched = d.execute_script("return performance.getEntriesByType('resource').map(e => e.name);")
        assert any("/clmap.png" in u for u in fetched) and any("/path?max_points=" in u for u in fetched), fetched
        assert not any(u.split("?")[0].endswith("/gcode") for u in fetched), f"the page downloaded a program: {fetched}"
        if not args.mock:
            assert os.path.exists(os.path.join(daemon.data, "state", "journal.sqlite")), "the journal is not in data_dir"
        d.execute_script("document.getElementById('preview').scrollIntoView()")
        p.shot("03-ready-preview")
        say(f"job #{job_id} ready: {meta}")

        # ---- start on the sim and see it through to 100 %
        p.click(f"#queue li[data-job='{job_id}'] button[data-act=start]")
        p.wait("the job to run", lambda: p.q("#progressbar").get_attribute("data-state") in ("running", "done"), 20)
        d.execute_script("window.scrollTo(0, 0)")
        if p.q("#progressbar").get_attribute("data-state") == "running":
            p.shot("04-running")
        p.wait("the job to finish", lambda: p.q("#progressbar").get_attribute("data-state") == "done", 240)
        assert p.text("#progress-pct") == "100 %", p.text("#progress-pct")
        lines = p.text("#progress-lines").replace(",", "").replace("\u202f", "").split(" ")
        assert lines[0] == lines[2] and int(lines[0]) > 1000, f"answered lines {p.text('#progress-lines')}"
        assert p.q("#progressbar").get_attribute("aria-valuenow") == "100"
        p.wait("the job in the history as done", lambda: d.find_elements(By.CSS_SELECTOR, f"#history tr[data-job='{job_id}'][data-state=done]"), 10)
        p.wait("the machine idle after the job", lambda: p.state() == "idle", 30)
        p.shot("05-done")
        say(f"job #{job_id} done: {p.text('#progress-lines')}")

        # ---- a line the controller rejects: explained in words, with what to do
        p.q("#console-input").send_keys("G99")
        p.click("#console-form button")
        banner = ".banner.error"
        p.wait("an error banner for the rejected console line", lambda: d.execute_script(
            f"return [...document.querySelectorAll('{banner}')].some(b => /error 20/.test(b.textContent))"), 20)
        texts = d.execute_script(f"""const b = [...document.querySelectorAll('{banner}')].find(b => /error 20/.test(b.textContent));
            return [b.querySelector('.b-title').textContent, b.querySelector('.b-text').textContent, b.querySelector('.b-todo').textContent];""")
        say(f"error banner: {texts}")
        assert all(t.strip() for t in texts) and "Unsupported" in texts[0], texts
        assert "> G99" in p.text("#console"), p.text("#console")
        d.execute_script("window.scrollTo(0, 0)")
        p.shot("06-error-banner")
        p.click(f"{banner} button[aria-label=Dismiss]")
        p.wait("the banner dismissed", lambda: not d.find_elements(By.CSS_SELECTOR, banner), 5)

        # ---- the real-time simulator from here: switch machines in the page
        Select(p.q("#machine-select")).select_by_value("bench")
        p.wait("the page to show the bench machine, idle", lambda: p.d.execute_script("return window.cncstream.state.current") == "bench" and p.connected(), 20)

        # ---- a G-code file dropped on the drop zone, queued as it is: start, hold and
        # resume with the running panel's buttons, stop with the jog pad's STOP; queued again and removed
        square = "G21 G90 G94\nG0 X0 Y0\n" + "G1 X40 F500\nG1 Y40\nG1 X0\nG1 Y0\n" * 3 + "M2\n"  # ~1 min at 500 mm/min
        drop_text_file(d, "square.nc", square)
        p.wait("the dropped G-code to be offered for the queue of bench",
               lambda: "square.nc: G-code" in p.text("#upload-status") and p.text("#tp-generate") == "Add to the queue of bench", 20)

        def queue_gcode():
            p.click("#tp-generate")
            sel = "#queue li[data-state=ready]"
            p.wait("the G-code job ready in the queue", lambda: d.execute_script(
                f"const e = document.querySelector('{sel} .title'); return e && e.textContent.startsWith('square.nc')"), 20)
            return d.execute_script(f"return document.querySelector('{sel}').dataset.job")

        def panel_state():
            return p.q("#progressbar").get_attribute("data-state")
        gid = queue_gcode()
        p.click(f"#queue li[data-job='{gid}'] button[data-act=start]")
        p.wait("the G-code job running", lambda: panel_state() == "running" and p.state() == "run", 20)
        p.click("#btn-hold")
        # Hold:1 is the feed hold slowing down, Hold:0 the machine standing still.
        p.wait("the job held and the machine still", lambda: panel_state() == "held" and p.q("#state").get_attribute("data-text") == "Hold:0", 20)
        assert p.text("#state") == "Held", p.text("#state")
        y_held = p.dro("y"), p.dro("x")
        seq = p.status_seq()
        p.wait("three status reports while held", lambda: (p.status_seq() or 0) >= (seq or 0) + 3, 10)
        assert (p.dro("y"), p.dro("x")) == y_held, "the machine moved while held"
        assert p.q("#btn-resume").is_enabled() and not p.q("#btn-hold").is_enabled()
        d.execute_script("window.scrollTo(0, 0)")
        p.shot("07-job-held")
        p.click("#btn-resume")
        p.wait("the job running again", lambda: panel_state() == "running" and p.state() == "run", 20)
        assert p.q("#btn-stop").is_enabled()
        # The jog pad's big STOP, the one a hand finds first, must stop a job too.
        p.click("#jog-stop")
        p.wait("the job stopped", lambda: panel_state() == "stopped", 30)
        p.wait("the stopped job in the history", lambda: d.find_elements(By.CSS_SELECTOR, f"#history tr[data-job='{gid}'][data-state=stopped]"), 10)
        p.wait("the machine idle after the stop", lambda: p.state() == "idle", 30)
        say(f"G-code job #{gid}: held, resumed, stopped at {p.text('#progress-lines')}")
        gid2 = queue_gcode()
        p.click(f"#queue li[data-job='{gid2}'] button[data-act=cancel]")
        p.wait("the removed job in the history as cancelled", lambda: d.find_elements(By.CSS_SELECTOR, f"#history tr[data-job='{gid2}'][data-state=cancelled]"), 10)
        assert not d.find_elements(By.CSS_SELECTOR, f"#queue li[data-job='{gid2}']"), "the cancelled job is still queued"

        # ---- a step jog: the DRO moves by exactly the step
        p.click(d.find_element(By.CSS_SELECTOR, "input[name=jogstep][value='10']").find_element(By.XPATH, ".."))
        x0 = p.dro("x")
        p.click("#jogpad [data-axis=X][data-dir='1']")
        p.wait("X to move by the 10 mm step", lambda: p.dro("x") is not None and abs(p.dro("x") - (x0 + 10)) < 0.002, 20)
        wait_stopped(p, "x")
        say(f"step jog: X {x0} -> {p.dro('x')}")

        # ---- an alarm: Reset during a step jog (GRBL's alarm 3, position lost); the
        # banner explains it and says what to do; Unlock clears it
        p.click("#jogpad [data-axis=X][data-dir='-1']")
        p.wait("the step jog moving", lambda: p.state() == "jog", 10)
        p.click("#reset")
        alarm = ".banner.alarm"
        p.wait("the alarm banner", lambda: d.find_elements(By.CSS_SELECTOR, alarm) and p.state() == "alarm", 20)
        texts = d.execute_script(f"""const b = document.querySelector('{alarm}');
            return [b.querySelector('.b-title').textContent, b.querySelector('.b-text').textContent,
                    b.querySelector('.b-todo').textContent, [...b.querySelectorAll('button')].map(x => x.textContent)];""")
        say(f"alarm banner: {texts}")
        assert "ALARM" in texts[0] and texts[1].strip() and texts[2].strip(), texts
        assert "Unlock" in texts[3] and "Home" in texts[3], f"a lost position should offer Home and Unlock: {texts[3]}"
        assert p.q("#jogpad [data-axis=X][data-dir='1']").get_attribute("disabled") is not None, "jogging must be off in alarm"
        d.execute_script("window.scrollTo(0, 0)")
        p.shot("08-alarm")
        unlock = d.execute_script(f"return [...document.querySelectorAll('{alarm} button')].find(b => b.textContent === 'Unlock')")
        p.click(unlock)
        p.wait("the alarm cleared", lambda: not d.find_elements(By.CSS_SELECTOR, alarm) and p.state() == "idle", 20)

        # ---- overrides: feed +10 % shows in the status, 100 resets it
        p.click("[data-ov=feed][data-delta='10']")
        p.wait("the feed override at 110 %", lambda: p.text("#ov-feed") == "110 %", 10)
        p.click("[data-ov=feed][data-delta='0']")
        p.wait("the feed override back at 100 %", lambda: p.text("#ov-feed") == "100 %", 10)

        # ---- press and hold: moves for longer than one lease, stops on release
        p.click(d.find_element(By.CSS_SELECTOR, "input[name=jogstep][value=hold]").find_element(By.XPATH, ".."))
        feed = 1200  # mm/min: the daemon clamps to the machine's rates ($110-$112, 500 on the simulator)
        p.q("#jog-feed").clear()
        p.q("#jog-feed").send_keys(str(feed))
        y0 = p.dro("y")
        btn = p.q("#jogpad [data-axis=Y][data-dir='1']")
        d.execute_script("arguments[0].scrollIntoView({block: 'center'})", btn)
        ActionChains(d).click_and_hold(btn).perform()
        t_press = time.monotonic()
        p.wait("the state to show Jog while held", lambda: p.state() == "jog", 10)
        # 15 mm takes seconds at these feeds, many 0.3 s leases: only a renewed jog gets there.
        p.wait("Y to move 15 mm while held", lambda: p.dro("y") - y0 > 15, 20)
        assert p.state() == "jog", f"state {p.state()} while still held"
        p.shot("09-jog-held")
        ActionChains(d).release().perform()
        t_release = time.monotonic()
        y1 = wait_stopped(p, "y")
        say(f"hold jog: Y {y0} -> {y1} in a {t_release - t_press:.1f} s hold")
        assert y1 - y0 > 15

        # ---- a hold ended by the window losing focus (the mouse stays down)
        ActionChains(d).click_and_hold(btn).perform()
        p.wait("the state to show Jog while held", lambda: p.state() == "jog", 10)
        d.execute_script("window.dispatchEvent(new Event('blur'))")
        y2 = wait_stopped(p, "y")
        ActionChains(d).release().perform()
        assert not d.find_elements(By.CSS_SELECTOR, "#jogpad .held"), "a jog button still shows held"
        say(f"blur released the jog: Y {y1} -> {y2}")

        # ---- the daemon's dead man: the page's messages stop reaching it while the
        # button is still held (a stalled network); the lease runs out and the jog stops.
        ActionChains(d).click_and_hold(btn).perform()
        p.wait("the state to show Jog while held", lambda: p.state() == "jog", 10)
        d.execute_script("const ws = window.cncstream.state.ws; ws.send = () => {};")
        y3 = wait_stopped(p, "y")
        assert d.find_elements(By.CSS_SELECTOR, "#jogpad .jog.held"), "the button should still be held"
        ActionChains(d).release().perform()
        d.execute_script("delete window.cncstream.state.ws.send;")  # the network is back
        say(f"silence stopped the jog (lease): Y {y2} -> {y3}")
        p.shot("10-after-jog")
        p.full_shot("11-desktop-full")

        # ---- a phone: 390x844 CSS pixels, touch
        d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {"width": 390, "height": 844, "deviceScaleFactor": 2, "mobile": True})
        d.execute_cdp_cmd("Emulation.setTouchEmulationEnabled", {"enabled": True, "maxTouchPoints": 5})
        d.get(daemon.url)
        p.wait("the page to connect on the phone", p.connected, 30)
        geo = d.execute_script("""
            const r = (s) => { const b = document.querySelector(s).getBoundingClientRect(); return [b.left, b.right, b.width, b.height]; };
            return {scrollW: document.documentElement.scrollWidth, innerW: window.innerWidth,
                    dro: r('#dro'), pad: r('#jogpad'),
                    buttons: [...document.querySelectorAll('#jogpad .jog')].map(b => { const x = b.getBoundingClientRect(); return [x.width, x.height, x.right]; }),
                    droFont: getComputedStyle(document.querySelector('#dro-x')).fontFamily};""")
        say(f"phone geometry: {geo}")
        assert geo["innerW"] == 390, geo
        assert geo["scrollW"] <= geo["innerW"], f"horizontal scrolling on the phone: content {geo['scrollW']} px > {geo['innerW']} px"
        for name in ("dro", "pad"):
            left, right, w, h = geo[name]
            assert left >= 0 and right <= 390 and w > 200 and h > 100, f"{name} does not fit the phone: {geo[name]}"
        for w, h, right in geo["buttons"]:
            assert w >= 44 and h >= 44 and right <= 390, f"a jog button is too small or off screen: {w}x{h} at {right}"
        assert "mono" in geo["droFont"].lower(), geo["droFont"]
        p.shot("12-phone-top")
        # The plaque's preview on the phone: a picture sized for the screen, nothing wider than it.
        d.execute_script("window.cncstream.showPreview(Number(arguments[0]))", job_id)
        p.wait("the preview on the phone", lambda: p.q("#preview").is_displayed() and p.q("#preview").get_attribute("data-job") == job_id, 30)
        pg = d.execute_script("""
            const i = document.getElementById('preview-img'), c = document.getElementById('preview-canvas').getBoundingClientRect();
            return {natural: [i.naturalWidth, i.naturalHeight], canvas: [c.left, c.right], scrollW: document.documentElement.scrollWidth};""")
        say(f"phone preview: {pg}")
        assert 0 < max(pg["natural"]) <= 2 * 390, f"the preview picture is not sized for the phone: {pg}"
        assert pg["canvas"][0] >= 0 and pg["canvas"][1] <= 390 and pg["scrollW"] <= 390, f"the preview does not fit the phone: {pg}"
        d.execute_script("document.getElementById('preview').scrollIntoView()")
        p.shot("12b-phone-preview")
        d.execute_script("document.getElementById('panel-jog').scrollIntoView()")
        p.shot("13-phone-jog")

        # ---- a finger on the phone: touch and hold Y-, the machine moves; lift, it stops
        p.click(d.find_element(By.CSS_SELECTOR, "input[name=jogstep][value=hold]").find_element(By.XPATH, ".."))
        btn = p.q("#jogpad [data-axis=Y][data-dir='-1']")
        d.execute_script("arguments[0].scrollIntoView({block: 'center'})", btn)
        r = d.execute_script("const b = arguments[0].getBoundingClientRect(); return [b.left + b.width / 2, b.top + b.height / 2];", btn)
        finger = [{"x": r[0], "y": r[1], "id": 1}]
        y0 = p.dro("y")
        d.execute_cdp_cmd("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": finger})
        try:
            p.wait("the state to show Jog under the finger", lambda: p.state() == "jog", 10)
            p.wait("Y to move 3 mm under the finger", lambda: y0 - p.dro("y") > 3, 20)
        finally:
            d.execute_cdp_cmd("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
        y1 = wait_stopped(p, "y")
        say(f"touch jog on the phone: Y {y0} -> {y1}")
        p.full_shot("14-phone-full")
        d.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})
        errs = p.console_errors()
        assert not errs, f"errors in the browser console: {errs}"
        return p.shots
    except Exception:
        p.keep_failure("main")
        raise
    finally:
        d.get("about:blank")  # leave before the daemon goes, or the page's reconnects are logged as errors
        daemon.stop()


def token_flow(args, out, d):
    """Off loopback the daemon needs a token: the page takes it from the URL
    fragment, else asks for it, and keeps it for the tab only."""
    daemon = Daemon(args, out, "daemon-token", require_token=True)
    p = Page(d, out)
    p.console_errors()  # reading the log empties it: what follows belongs to this part
    try:
        # From the fragment: connects, and the token leaves the address bar.
        d.get(daemon.url + "#token=" + daemon.token)
        p.wait("the page to connect with the token from the URL", p.connected, 30)
        assert "token" not in d.current_url, d.current_url
        assert d.execute_script("return sessionStorage.getItem('cncstream.token')") == daemon.token
        # A fresh tab state with no token: the page asks; the typed token works.
        d.execute_script("sessionStorage.clear()")
        d.get(daemon.url)
        alert = p.wait("the page to ask for the token", lambda: _alert(d), 20)
        alert.send_keys(daemon.token)
        alert.accept()
        p.wait("the page to connect with the typed token", p.connected, 30)
        p.shot("15-token-prompt-connected")
        # Cancelled: no prompt at every reconnect, a banner that asks again when pressed.
        d.execute_script("sessionStorage.clear()")
        d.get(daemon.url)
        p.wait("the page to ask for the token", lambda: _alert(d), 20).dismiss()
        p.wait("the token banner", lambda: d.find_elements(By.CSS_SELECTOR, ".banner[data-key=token]"), 20)
        assert not p.connected()
        p.shot("16-token-declined")
        p.click(d.execute_script("return [...document.querySelectorAll('.banner[data-key=token] button')].find(b => b.textContent === 'Enter the token')"))
        alert = p.wait("the page to ask again", lambda: _alert(d), 20)
        alert.send_keys(daemon.token)
        alert.accept()
        p.wait("the page to connect after the banner", p.connected, 30)
        assert not d.find_elements(By.CSS_SELECTOR, ".banner[data-key=token]"), "the token banner stayed"
        errs = [e for e in p.console_errors() if "401" not in e["message"]]  # the first, refused request is expected
        assert not errs, f"errors in the browser console: {errs}"
    except Exception:
        p.keep_failure("token")
        raise
    finally:
        d.get("about:blank")  # leave before the daemon goes, or the page's reconnects are logged as errors
        daemon.stop()


# A machine whose tool change is the operator's (manual): two tools of unequal
# stick-out, a probe plane at machine Z 10 (a touch plate under the tool,
# 5 mm thick), the change's travel at machine Z 30.
TOOL_CHANGE_MACHINE = ('[[machine]]\nname = "tc"\nport = "sim"\nsim_speed = "max"\n'
                       'sim_tool_table = "1=flat:6@30,2=ball:3@37.3"\nsim_probe_surface_z = 10\n'
                       '[machine.tool_change]\nmethod = "manual"\nsafe_z = 30\nplate_thickness = 5\n')
TWO_TOOLS = ("G21 G90\nT1\nG0 Z5\nG1 X10 F500\n(finishing: 3 mm ball nose)\nT2\nM0\n"
             "G0 Z5\nG1 X20 F500\nG1 Y10\nM2\n")


def tool_change_flow(args, out, d):
    """The issue's test: the prompt appears at the change, jog and probe work,
    continue resumes the job (against the real daemon's simulated machine)."""
    daemon = Daemon(args, out, "daemon-toolchange", machines=TOOL_CHANGE_MACHINE)
    p = Page(d, out)
    d.get("about:blank")  # no page of an earlier flow still reconnecting to its stopped daemon
    p.console_errors()  # reading the log empties it: what follows belongs to this flow
    try:
        # T2 is in the daemon's tool library: the panel shows its name and expected stick-out.
        add = urllib.request.Request(daemon.url + "api/v1/tools", method="POST", headers={"Content-Type": "application/json"},
                                     data=json.dumps({"number": 2, "name": "3 mm ball finisher", "shape": "ball:3",
                                                      "stick_out": 37.3}).encode())
        with urllib.request.urlopen(add, timeout=10) as r:
            assert r.status == 201, r.status
        d.get(daemon.url)
        p.wait("the page to connect to the tool-change machine", p.connected, 30)
        drop_text_file(d, "two-tools.nc", TWO_TOOLS)
        p.wait("the G-code offered for the queue", lambda: "two-tools.nc: G-code" in p.text("#upload-status"), 20)
        p.click("#tp-generate")
        sel = "#queue li[data-state=ready]"
        p.wait("the job ready", lambda: d.find_elements(By.CSS_SELECTOR, sel), 20)
        jid = d.execute_script(f"return document.querySelector('{sel}').dataset.job")
        assert not p.q("#panel-toolchange").is_displayed(), "the tool-change panel shows before any change"
        p.click(f"#queue li[data-job='{jid}'] button[data-act=start]")

        # ---- the prompt appears at the change, with its steps and the tool
        p.wait("the tool-change panel at the operator's step",
               lambda: p.q("#panel-toolchange").is_displayed() and
               p.q("#panel-toolchange").get_attribute("data-step") == "zero_manually", 30)
        assert p.q("#panel-toolchange").get_attribute("data-line") == "7"
        what, prompt = p.text("#tc-what"), p.text("#tc-prompt")
        say(f"tool change: {what} / {prompt}")
        assert what.startswith("T2") and "finishing: 3 mm ball nose" in what and "line 7" in what, what
        assert "mount T2" in prompt, prompt
        library = p.text("#tc-library")
        assert "3 mm ball finisher" in library and "37.3 mm" in library, library
        steps = d.execute_script("return [...document.querySelectorAll('#tc-steps li')].map(l => [l.className, l.dataset.step])")
        assert steps[0] == ["done", "before"] and steps[1] == ["current", "zero_manually"], steps
        assert p.q("#tc-confirm").is_enabled() and p.q("#tc-probe").is_enabled()
        assert p.q("#progressbar").get_attribute("data-state") == "running"
        d.execute_script("window.scrollTo(0, 0)")
        p.shot("20-tool-change-prompt")

        # ---- the jog pad is live at the prompt: a 1 mm step down moves Z by 1 mm
        p.click(d.find_element(By.CSS_SELECTOR, "input[name=jogstep][value='1']").find_element(By.XPATH, ".."))
        zdown = p.q("#jogpad [data-axis=Z][data-dir='-1']")
        p.wait("the jog pad enabled at the prompt", zdown.is_enabled, 10)
        z0 = p.dro("z")
        p.click(zdown)
        p.wait("Z to move down by the 1 mm step", lambda: abs(p.dro("z") - (z0 - 1)) < 0.002, 20)
        wait_stopped(p, "z")
        say(f"jog at the prompt: Z {z0} -> {p.dro('z')}")

        # ---- probe: down onto the plate, work Z set to its 5 mm thickness at the touch
        p.click("#tc-probe")
        p.wait("work Z at the plate's thickness after the probe (and its 2 mm retract)",
               lambda: p.dro("z") is not None and abs(p.dro("z") - 7.0) < 0.01 and p.state() == "idle", 30)
        mz = p.dro("mz")
        say(f"probed: work Z {p.dro('z')}, machine Z {mz}")
        # T2's tip is 7.3 mm below T1's: the plate (machine Z 10) touched with the spindle at 17.3.
        assert abs(mz - (17.3 + 2)) < 0.01, mz
        assert p.q("#panel-toolchange").get_attribute("data-step") == "zero_manually"
        p.shot("21-tool-change-probed")

        # ---- continue resumes the job: the panel goes, the job runs to its end
        p.click("#tc-confirm")
        p.wait("the panel gone after continue", lambda: not p.q("#panel-toolchange").is_displayed(), 30)
        p.wait("the job done", lambda: p.q("#progressbar").get_attribute("data-state") == "done", 60)
        p.wait("the machine idle after the job", lambda: p.state() == "idle", 30)
        # The last move ran with T2 zeroed on the plate: work Y 10 at work Z 5 (machine Z 5 + 12.3).
        assert abs(p.dro("y") - 10) < 0.002 and abs(p.dro("z") - 5) < 0.002, (p.dro("y"), p.dro("z"))
        assert abs(p.dro("mz") - 17.3) < 0.01, p.dro("mz")
        assert "tool change: the operator zeroed Z with T2" in p.text("#console"), p.text("#console")
        d.execute_script("window.scrollTo(0, 0)")
        p.shot("22-tool-change-done")

        # ---- start from a line: the machine is moved away, the same job continues
        # after line 9 (its position there is X20 Y0), planned on its preview, queued, started
        p.click(d.find_element(By.CSS_SELECTOR, "input[name=jogstep][value='10']").find_element(By.XPATH, ".."))
        p.click("#jogpad [data-axis=X][data-dir='-1']")
        p.wait("X jogged to 10", lambda: abs(p.dro("x") - 10) < 0.002, 20)
        wait_stopped(p, "x")
        d.execute_script("window.cncstream.showPreview(Number(arguments[0]))", jid)
        p.wait("the preview of the finished job", lambda: p.q("#preview").is_displayed() and p.q("#preview").get_attribute("data-job") == jid, 30)
        p.q("#from-line").send_keys("9")
        p.click("#from-line-form button")
        p.wait("the plan shown", lambda: p.q("#from-line-plan").is_displayed(), 20)
        plan_text, preamble = p.text("#from-line-text"), p.text("#from-line-preamble")
        say(f"plan: {plan_text} / {preamble!r}")
        assert "after line 9" in plan_text, plan_text
        # Up to the program's safe height first, then over the line's position.
        pre = preamble.replace(".000", "").splitlines()
        assert "G0 Z5" in pre and "G0 X20 Y0" in pre and pre.index("G0 Z5") < pre.index("G0 X20 Y0"), preamble
        p.shot("23-start-from-a-line-plan")
        p.click("#from-line-queue")
        ready_new = f"#queue li[data-state=ready]"
        p.wait("the start-from-a-line job queued", lambda: d.find_elements(By.CSS_SELECTOR, ready_new), 20)
        rid = d.execute_script(f"return document.querySelector('{ready_new}').dataset.job")
        assert rid != jid
        p.click(f"#queue li[data-job='{rid}'] button[data-act=start]")
        p.wait("the history to show it done", lambda: d.find_elements(By.CSS_SELECTOR, f"#history tr[data-job='{rid}'][data-state=done]"), 60)
        p.wait("the machine idle", lambda: p.state() == "idle", 30)
        assert abs(p.dro("x") - 20) < 0.002 and abs(p.dro("y") - 10) < 0.002, (p.dro("x"), p.dro("y"))
        say(f"started after line 9: ended at X {p.dro('x')} Y {p.dro('y')}")
        errs = p.console_errors()
        assert not errs, f"errors in the browser console: {errs}"
    except Exception:
        p.keep_failure("toolchange")
        raise
    finally:
        d.get("about:blank")
        daemon.stop()


# ---- what every page test's main() does (test_tools_page.py, test_shop_page.py, test_setup_page.py)
def page_test_args(output_name, extra=None):
    """The common options (--daemon, --source, --output) and any the test adds."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--daemon", default=os.environ.get("CNCSTREAMD"), help="the cncstreamd binary")
    ap.add_argument("--source", default=os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")))
    ap.add_argument("--output", default=os.path.join(os.getcwd(), "test-output", output_name))
    if extra:
        extra(ap)
    args = ap.parse_args()
    args.mock = False
    return args


def have_programs(*named):
    """(what, path) pairs: False, saying which, when one is not an executable."""
    for name, path in named:
        if not (path and os.access(path, os.X_OK)):
            print(f"FAIL: no {name} to test: {path!r}")
            return False
    return True


def fresh_output(out, exts):
    """The artefacts are this run's: none of an earlier run left to mislead."""
    os.makedirs(out, exist_ok=True)
    for f in os.listdir(out):
        if f.endswith(exts):
            os.remove(os.path.join(out, f))


def run_in_browser(args, flow):
    """flow(d) in a fresh headless Chromium; 0 passed, 1 failed (the trace printed)."""
    d = None
    try:
        d = browser()
        flow(d)
    except Exception:
        traceback.print_exc()
        say(f"FAILED; screenshots and logs in {args.output}")
        return 1
    finally:
        if d:
            d.quit()
    say(f"passed in {time.monotonic() - T0:.1f} s; screenshots in {args.output}")
    return 0


def _alert(d):
    try:
        a = d.switch_to.alert
        a.text  # raises when there is none
        return a
    except Exception:
        return None


def main():
    ap = argparse.ArgumentParser()
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--daemon", default=os.environ.get("CNCSTREAMD"), help="the cncstreamd binary")
    ap.add_argument("--source", default=os.path.normpath(os.path.join(here, "..", "..")))
    ap.add_argument("--output", default=os.environ.get("CNCSTREAM_TEST_OUTPUT", os.path.join(os.getcwd(), "test-output", "web")))
    ap.add_argument("--mock", action="store_true", help="run against tests/web/mock_daemon.py (development only)")
    ap.add_argument("--only", choices=["main", "token", "toolchange"], help="run one flow (development)")
    args = ap.parse_args()
    if not args.mock and not (args.daemon and os.access(args.daemon, os.X_OK)):
        print(f"FAIL: no cncstreamd to test (--daemon or CNCSTREAMD): {args.daemon!r}")
        return 1
    os.makedirs(args.output, exist_ok=True)
    # The artefacts are this run's: no screenshot of an earlier run left to mislead.
    for f in os.listdir(args.output):
        if f.endswith((".png", ".log", ".html")):
            os.remove(os.path.join(args.output, f))
    d = browser()
    try:
        shots = []
        if args.only in (None, "main"):
            shots = main_flow(args, args.output, d)
        if args.only in (None, "token"):
            token_flow(args, args.output, d)
        if args.only in (None, "toolchange"):
            if args.mock:
                say("the tool-change flow needs the real daemon's simulator: not run with --mock")
            else:
                tool_change_flow(args, args.output, d)
    except Exception:
        traceback.print_exc()
        say(f"FAILED; screenshots and logs in {args.output}")
        return 1
    finally:
        d.quit()
    say(f"passed; screenshots: {', '.join(os.path.basename(s) for s in shots)} in {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
