#!/usr/bin/python3
"""The web page's tool library (web/tools.js) in headless Chromium against a
real cncstreamd with a fresh data folder:

  the Tools panel shows the empty library -> a tool added through its form
  (a bad shape first: the daemon's words shown at the form) is listed ->
  edited (name, stick-out), in the daemon's library too -> picked in the
  tool-path form for an uploaded STL, whose job is generated with that
  tool's spec; the roughing and rest fields offer it -> deleted, gone from
  the list and the picker -> a LinuxCNC tool table imported from a file,
  what was understood and skipped shown.

Exit codes: 0 passed, 1 failed, 77 skipped (no Chromium, as test_page.py).

  test_tools_page.py --daemon build/release/cncstreamd --source . --output DIR
"""
import json
import os
import sys
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_page as tp  # noqa: E402  (exits 77 when Chromium is missing)
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

say = tp.say

# A 20 x 20 mm pyramid, 5 mm high: generated in a moment.
PYRAMID = "solid pyramid\n" + "".join(
    f"facet normal 0 0 0\nouter loop\nvertex {a}\nvertex {b}\nvertex 10 10 5\nendloop\nendfacet\n"
    for a, b in (("0 0 0", "20 0 0"), ("20 0 0", "20 20 0"), ("20 20 0", "0 20 0"), ("0 20 0", "0 0 0"))) + \
    "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 20 20 0\nvertex 20 0 0\nendloop\nendfacet\n" \
    "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 20 0\nvertex 20 20 0\nendloop\nendfacet\nendsolid pyramid\n"

# One tool understood, one entry skipped (no diameter).
TOOL_TABLE = "T5 P5 Z40 D3.175 ;1/8 ball nose\nT6 Z2 ;probe\n"


def get_json(daemon, path):
    with urllib.request.urlopen(daemon.url + "api/v1" + path, timeout=10) as r:
        return json.loads(r.read())


def tools_flow(args, out, d):
    daemon = tp.Daemon(args, out, "daemon-tools", machines='[[machine]]\nname = "sim"\nport = "sim"\nsim_speed = "max"\n')
    p = tp.Page(d, out)
    try:
        def fill(css, v):
            e = p.q(css)
            e.clear()
            e.send_keys(str(v))

        def row(n):
            return f'#tools-table tr[data-tool="{n}"]'

        def text_of(css):
            """An element's text read at once ('' when none): the list is rebuilt after each change."""
            return d.execute_script("const e = document.querySelector(arguments[0]); return e ? e.textContent : ''", css)

        d.get(daemon.url)
        p.wait("the page to connect", p.connected, 30)
        p.wait("the empty library", lambda: "library is empty" in text_of("#tools-table tbody"), 10)

        # ---- add: a bad shape is refused in the daemon's words, then the tool is saved and listed
        p.click("#tools-new")
        p.wait("the tool form", lambda: p.q("#tools-form").is_displayed(), 5)
        fill("#tool-name", "1/8 tapered ball")
        fill("#tool-shape", "taper:1:95:3.175")
        fill("#tool-stick-out", "30")
        p.click("#tools-save")
        p.wait("the daemon's refusal at the form", lambda: "shape:" in p.text("#tools-form-status"), 10)
        say(f"refused: {p.text('#tools-form-status')}")
        assert "tools-error" in p.q("#tools-form-status").get_attribute("class")
        assert p.q("#tools-form").is_displayed(), "the form stays open after a refusal"
        fill("#tool-shape", "taper:1:5:3.175")
        p.click("#tools-save")
        p.wait("T1 listed", lambda: d.find_elements(By.CSS_SELECTOR, row(1)), 10)
        assert not p.q("#tools-form").is_displayed()
        text = text_of(row(1))
        assert "1/8 tapered ball" in text and "taper:1:5:3.175" in text and "30 mm" in text, text

        # ---- edit: the name and the stick-out; the daemon's library has them
        p.click(f'{row(1)} button[data-act="edit"]')
        p.wait("the form for T1", lambda: p.text("#tools-form-title") == "Edit T1", 5)
        assert not p.q("#tool-number").is_enabled(), "a tool keeps its number"
        fill("#tool-name", "1/8 tapered ball long")
        fill("#tool-stick-out", "32.5")
        p.click("#tools-save")
        p.wait("T1 edited in the list", lambda: "32.5 mm" in text_of(row(1)) and "long" in text_of(row(1)), 10)
        t1 = get_json(daemon, "/tools/1")
        assert t1["name"] == "1/8 tapered ball long" and t1["stick_out"] == 32.5 and t1["shape"] == "taper:1:5:3.175", t1
        p.shot("tools-listed")

        # ---- pick it in the tool-path form: the job is generated with T1's spec
        tp.drop_text_file(d, "pyramid.stl", PYRAMID)
        p.wait("the tool-path form", lambda: p.q("#toolpath-form").is_displayed(), 20)
        offered = d.execute_script("return [...document.querySelectorAll('#tool-library-list option')].map(o => o.value)")
        assert offered == ["T1"], offered
        assert p.q("#tp-rough").get_attribute("list") == "tool-library-list" and \
            p.q("#tp-rest").get_attribute("list") == "tool-library-list"
        Select(p.q("#tp-library")).select_by_value("T1")
        assert not p.q("#tp-diameter").is_enabled(), "the typed cutter is not used with a library tool"
        p.click("#tp-generate")
        p.wait("the job made", lambda: d.execute_script("return window.cncstream.state.lastGenerated") is not None, 10)
        jid = d.execute_script("return window.cncstream.state.lastGenerated")
        p.wait("the job generated", lambda: p.q("#tp-status").get_attribute("data-state") in ("ready", "failed"), 30)
        job = get_json(daemon, f"/jobs/{jid}")
        assert job["state"] == "ready", job
        assert job["params"]["tool"] == "taper:1:5:3.175", job["params"]
        say(f"job #{jid} generated with {job['params']['tool']}")

        # ---- delete it: gone from the list, the library and the picker
        p.click(f'{row(1)} button[data-act="delete"]')
        alert = p.wait("the confirmation", lambda: tp._alert(d), 5)
        assert "T1" in alert.text, alert.text
        alert.accept()
        p.wait("the library empty again", lambda: "library is empty" in text_of("#tools-table tbody"), 10)
        assert get_json(daemon, "/tools")["tools"] == []
        assert p.q("#tp-library").get_attribute("value") == "" and p.q("#tp-diameter").is_enabled()
        assert d.execute_script("return document.querySelectorAll('#tool-library-list option').length") == 0

        # ---- import a LinuxCNC tool table: what was understood and what skipped, by entry
        table = os.path.abspath(os.path.join(out, "tool.tbl"))  # the browser wants an absolute path
        with open(table, "w") as f:
            f.write(TOOL_TABLE)
        p.q("#tools-import-file").send_keys(table)
        p.wait("the import's report", lambda: p.q("#tools-import-result").is_displayed(), 10)
        understood = p.text("#tools-import-result .tools-understood")
        skipped = p.text("#tools-import-result .tools-skipped")
        say(f"imported: {understood!r}; skipped: {skipped!r}")
        assert "T5" in understood and "ball:3.175" in understood, understood
        assert "T6" in skipped, skipped
        p.wait("T5 listed", lambda: d.find_elements(By.CSS_SELECTOR, row(5)), 10)
        # A malformed file: refused, naming the file and the place.
        with open(table, "w") as f:
            f.write("T5 D?\n")
        p.q("#tools-import-file").send_keys(table)
        p.wait("the refusal", lambda: "not imported" in p.text("#tools-status"), 10)
        assert "tool.tbl:1:" in p.text("#tools-status") and "cncstreamd-import" not in p.text("#tools-status"), \
            p.text("#tools-status")
        p.full_shot("tools-imported")
        # The refusals above are 4xx answers the browser logs as failed loads: anything else is a page error.
        errors = [e for e in p.console_errors() if "status of 40" not in e.get("message", "")]
        assert not errors, f"errors in the browser's console: {errors}"
    except Exception:
        p.keep_failure("tools")
        raise
    finally:
        daemon.stop()


def main():
    args = tp.page_test_args("web-tools")
    if not tp.have_programs(("cncstreamd (--daemon)", args.daemon)):
        return 1
    tp.fresh_output(args.output, (".png", ".log", ".tbl"))
    return tp.run_in_browser(args, lambda d: tools_flow(args, args.output, d))


if __name__ == "__main__":
    sys.exit(main())
