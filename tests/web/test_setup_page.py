#!/usr/bin/python3
"""The web page's set-up routines outside a job (web/routines.js) and the
start from a line picked on the preview, in headless Chromium against a real
cncstreamd whose simulated machine has a stock block with a corner plate on
its front-left corner and a tool-length sensor:

  the corner probed (X, Y and Z with a 6 mm flat) -> the result asked before
  it is written -> confirmed: work zero on the block's corner within 0.01 mm
  -> the tool-length reference measured on the sensor -> a job's outline (the
  hull of its moves) traced at its safe height -> a click on the job's
  preview picks the line of the nearest cut for the start from a line, and a
  typed line moves the marker.

Exit codes: 0 passed, 1 failed, 77 skipped (no Chromium, as test_page.py).

  test_setup_page.py --daemon build/release/cncstreamd --source . --output DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_page as tp  # noqa: E402  (exits 77 when Chromium is missing)
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

say = tp.say

# The block X20..120 Y20..100, top at machine Z -30; the corner plate (5 mm
# thick, its walls 3 mm outside the block) on its X-min/Y-min corner; the 6 mm
# flat over the plate at power-on. A sensor at machine X-30 Y0, its top at Z-10,
# within the 50 mm probe travel from the change height, machine Z 30.
CORNER = (20.0, 20.0, -30.0)
SETUP_MACHINE = ('[[machine]]\nname = "setup"\nport = "sim"\nsim_speed = "max"\n'
                 'sim_tool_table = "1=flat:6@30,2=flat:6@37.3"\n'
                 'sim_stock = "20,20,-50:120,100,-30"\nsim_corner_plate = "5,3"\nsim_start = "42,42,-15"\n'
                 'sim_tool_sensor = "-30,0,-10"\n'
                 '[machine.tool_change]\nmethod = "sensor"\nsensor_at = [-30, 0]\nsafe_z = 30\nprobe_travel = 50\n')
# A slot with a half-circle end: its hull has the arc's corners, its box an empty corner.
SLOT = "G21 G90\nG0 Z5\nG0 X10 Y10\nG1 Z-1 F300\nG1 X40\nG3 X40 Y30 I0 J10\nG1 X10\nG1 Y10\nG0 Z5\nM2\n"


def routine_done(p, says):
    """The routine over, its result shown and saying `says`."""
    return p.q("#rt-active").get_attribute("hidden") is not None and says in p.text("#rt-result")


def setup_flow(args, out, d):
    daemon = tp.Daemon(args, out, "daemon-setup", machines=SETUP_MACHINE)
    p = tp.Page(d, out)
    try:
        def fill(css, v):
            e = p.q(css)
            e.clear()
            e.send_keys(str(v))

        d.get(daemon.url)
        p.wait("the page to connect to the set-up machine", p.connected, 30)
        assert p.q("#rt-corner-go").is_enabled(), "the corner probe is off on an idle machine"

        # ---- the corner: asked first, written on confirm
        Select(p.q("#rt-corner-axes")).select_by_value("xyz")
        fill("#rt-corner-tool", "flat:6")
        fill("#rt-plate-thickness", 5)
        fill("#rt-plate-lip", 3)
        p.click("#rt-corner-go")
        p.wait("the corner probe's question", lambda: p.q("#rt-active").is_displayed() and p.text("#rt-prompt") != "", 60)
        prompt = p.text("#rt-prompt")
        say(f"corner probe asks: {prompt}")
        assert "corner probe" in prompt and "confirm" in prompt, prompt
        assert p.q("#rt-confirm").is_enabled() and not p.q("#rt-corner-go").is_enabled()
        p.shot("30-corner-question")
        p.click("#rt-confirm")
        p.wait("the corner probe done", lambda: routine_done(p, "G54 set to"), 60)
        result = p.text("#rt-result")
        say(f"corner probe: {result}")
        assert result.startswith("Done"), result
        p.wait("the machine idle", lambda: p.state() == "idle", 20)
        # Work zero is the block's corner: work = machine - corner, to the probe's resolution.
        w = [p.dro(a) for a in "xyz"]
        m = [p.dro("m" + a) for a in "xyz"]
        for a, wi, mi, ci in zip("XYZ", w, m, CORNER):
            assert abs(wi - (mi - ci)) < 0.01, f"{a}: work {wi}, machine {mi}, corner {ci}"
        p.shot("31-corner-done")

        # ---- the tool-length reference on the sensor
        p.click("#rt-tool summary")  # the section opens as a user would open it
        fill("#rt-in-spindle", 1)
        p.click("#rt-measure")
        p.wait("the reference measured", lambda: routine_done(p, "is the reference") and "T1" in p.text("#rt-reference"), 60)
        assert p.text("#rt-result").startswith("Done"), p.text("#rt-result")
        say(f"reference: {p.text('#rt-reference')}")

        # ---- the outline of a job in the preview: the hull, at its safe height
        tp.drop_text_file(d, "slot.nc", SLOT)
        p.wait("the G-code offered for the queue", lambda: "slot.nc: G-code" in p.text("#upload-status"), 20)
        p.click("#tp-generate")
        sel = "#queue li[data-state=ready]"
        p.wait("the job ready", lambda: d.find_elements(By.CSS_SELECTOR, sel), 20)
        jid = d.execute_script(f"return document.querySelector('{sel}').dataset.job")
        d.execute_script("window.cncstream.showPreview(Number(arguments[0]))", jid)
        p.wait("the preview drawn", lambda: p.q("#preview").get_attribute("data-job") == jid and
               d.execute_script("return !!window.cncstream.state.previewDraw"), 30)
        p.wait("the outline offered for the previewed job", lambda: p.q("#rt-outline-go").is_enabled(), 10)
        p.click("#rt-outline summary")
        Select(p.q("#rt-outline-shape")).select_by_value("hull")
        fill("#rt-outline-feed", 2000)
        p.click("#rt-outline-go")
        p.wait("the outline traced", lambda: routine_done(p, "traced the"), 60)
        result = p.text("#rt-result")
        say(f"outline: {result}")
        assert result.startswith("Done") and "hull" in result, result
        p.wait("the machine idle", lambda: p.state() == "idle", 20)
        assert abs(p.dro("z") - 5) < 0.002, f"the trace ends at work Z {p.dro('z')}, not the program's safe 5"

        # ---- a line picked on the preview: the arc's far end (X40 Y30) ends line 6
        x, y = d.execute_script("""const s = window.cncstream.state, c = document.getElementById('preview-canvas');
            const r = c.getBoundingClientRect();
            return [r.left + s.previewDraw.X(40) * r.width / c.width, r.top + s.previewDraw.Y(30) * r.height / c.height];""")
        d.execute_script("""document.getElementById('preview-canvas').dispatchEvent(
            new MouseEvent('click', {clientX: arguments[0], clientY: arguments[1], bubbles: true}));""", x, y)
        p.wait("the line picked on the preview", lambda: p.q("#from-line").get_attribute("value") == "6", 10)
        marker = d.execute_script("return window.cncstream.state.previewLine")
        assert marker and marker["line"] == 6 and abs(marker["x"] - 40) < 1e-6 and abs(marker["y"] - 30) < 1e-6, marker
        d.execute_script("document.getElementById('preview').scrollIntoView()")
        p.shot("32-line-picked-on-preview")
        # Typed: the marker goes to the last drawn point at or before the line (line 5 ends at X40 Y10).
        fill("#from-line", 5)
        p.wait("the marker at line 5's end", lambda: (d.execute_script("return window.cncstream.state.previewLine") or {}).get("y") == 10, 10)
        errs = p.console_errors()
        assert not errs, f"errors in the browser console: {errs}"
    except Exception:
        p.keep_failure("setup")
        raise
    finally:
        d.get("about:blank")
        daemon.stop()


def main():
    args = tp.page_test_args("web-setup")
    if not tp.have_programs(("cncstreamd (--daemon)", args.daemon)):
        return 1
    tp.fresh_output(args.output, (".png", ".log", ".html"))
    return tp.run_in_browser(args, lambda d: setup_flow(args, args.output, d))


if __name__ == "__main__":
    sys.exit(main())
