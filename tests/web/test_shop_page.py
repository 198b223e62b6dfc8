#!/usr/bin/python3
"""The web page's shop view in headless Chromium against a real cncstreamd
that joined a throw-away PostgreSQL hub (initdb into a temporary folder,
postgres on 127.0.0.1 and a free port, `cncstream shop init`):

  the page shows the Shop section with this daemon's machine -> a program
  submitted from the page's form appears in the shop's queue, pending ->
  its Cancel button moves it to cancelled (on the hub too) -> its
  "Requeue anywhere" button puts it back, pending -> a change made on the
  hub is drawn from the pushed `shop` frame while the page's own reads of
  the view are refused.

The daemon logs in as a PC (cncstream_pc) granted cncstream_web_operator,
as docs/shop.md tells a shop to do. PostgreSQL missing is a failure (the
setup script installs it); only a missing Chromium skips, as test_page.py.
Exit codes: 0 passed, 1 failed, 77 skipped.

  test_shop_page.py --daemon build/release/cncstreamd --cli build/release/cncstream --source . --output DIR
"""
import fcntl
import glob
import os
import pwd
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_page as tp  # noqa: E402  (exits 77 when Chromium is missing)
from selenium.webdriver.common.by import By  # noqa: E402

say = tp.say


def pg_program(name):
    """A PostgreSQL program from PATH or Debian's /usr/lib/postgresql/N/bin (the newest)."""
    found = shutil.which(name)
    if found:
        return found
    for d in sorted(glob.glob("/usr/lib/postgresql/*/bin"), reverse=True):
        if os.access(os.path.join(d, name), os.X_OK):
            return os.path.join(d, name)
    raise AssertionError(f"PostgreSQL's {name} is not installed: scripts/setup.sh installs postgresql")


class TempHub:
    """A throw-away PostgreSQL on loopback, run as 'postgres' when we are root
    (initdb and postgres refuse root), removed when stopped."""

    def __init__(self, out, template):
        self.dir = tempfile.mkdtemp(prefix="cncstream-web-hub-")
        self.user = None
        if os.geteuid() == 0:
            self.user = "postgres" if _has_user("postgres") else "nobody"
            os.chown(self.dir, pwd.getpwnam(self.user).pw_uid, -1)
        self.port = tp.free_port()
        self.log = open(os.path.join(out, "hub.log"), "w")
        data = os.path.join(self.dir, "data")
        self._copy_template(template, data)
        self.proc = subprocess.Popen([pg_program("postgres"), "-D", data, "-p", str(self.port), "-k", self.dir,
                                      "-c", "listen_addresses=127.0.0.1", "-c", "fsync=off",
                                      "-c", "synchronous_commit=off", "-c", "shared_buffers=16MB"],
                                     stdout=self.log, stderr=subprocess.STDOUT, user=self.user)
        deadline = time.monotonic() + 30
        while subprocess.run([pg_program("pg_isready"), "-q", "-h", "127.0.0.1", "-p", str(self.port)]).returncode != 0:
            if self.proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"PostgreSQL did not start: see {self.log.name}")
            time.sleep(0.05)  # polling a server that has no readiness signal of its own

    def _copy_template(self, template, data):
        """The cluster is initialised once per build folder (initdb takes seconds) and copied: the same
        template and lock as the C++ tests (tests/shop/shop_test_util.hpp)."""
        with open(template + ".lock", "a+") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not os.path.exists(os.path.join(template, "PG_VERSION")):
                work = template + ".new"
                shutil.rmtree(work, ignore_errors=True)
                os.makedirs(work)
                self._chown(work)
                say("initdb")
                subprocess.run([pg_program("initdb"), "-D", work, "-U", "postgres", "--auth=trust", "-E", "UTF8",
                                "--no-sync", "--locale=C"], check=True, stdout=self.log, stderr=subprocess.STDOUT,
                               user=self.user)
                shutil.rmtree(template, ignore_errors=True)
                os.rename(work, template)
            shutil.copytree(template, data, symlinks=True)
        os.chmod(data, 0o700)
        self._chown(data)
        for root, dirs, files in os.walk(data):
            for n in dirs + files:
                self._chown(os.path.join(root, n))

    def _chown(self, path):
        if self.user:
            os.lchown(path, pwd.getpwnam(self.user).pw_uid, pwd.getpwnam(self.user).pw_gid)

    def url(self, db="postgres", user="postgres"):
        return f"postgresql://{user}@127.0.0.1:{self.port}/{db}"

    def sql(self, statement, db="shop"):
        r = subprocess.run([pg_program("psql"), "-X", "-q", "-t", "-A", "-v", "ON_ERROR_STOP=1", "-d", self.url(db),
                            "-c", statement], capture_output=True, text=True)
        if r.returncode != 0:
            raise AssertionError(f"psql {statement!r}: {r.stderr.strip()}")
        return r.stdout.strip()

    def stop(self):
        tp.end_process(self.proc, 2)  # SIGINT: fast shutdown
        self.log.close()
        shutil.rmtree(self.dir, ignore_errors=True)


def _has_user(name):
    try:
        pwd.getpwnam(name)
        return True
    except KeyError:
        return False


def shop_flow(args, out, d, hub):
    hub.sql("CREATE DATABASE shop", db="postgres")
    init = subprocess.run([args.cli, "shop", "init", hub.url("shop")], capture_output=True, text=True)
    assert init.returncode == 0, f"cncstream shop init failed: {init.stdout}{init.stderr}"
    # The daemon's PC login, allowed by the shop to act from its web page (docs/shop.md, "Roles").
    hub.sql("CREATE ROLE pc_web LOGIN IN ROLE cncstream_pc, cncstream_web_operator")
    machines = ('[[machine]]\nname = "w1"\nport = "sim"\nsim_speed = "max"\n'
                'shop_claim = false\n'  # the submitted job stays in the shop's queue for the page to act on
                f'[shop]\nurl = "{hub.url("shop", "pc_web")}"\nname = "acme"\npc = "web-pc"\nheartbeat_s = 0.5\n')
    daemon = tp.Daemon(args, out, "shop-daemon", machines=machines)
    try:
        p = tp.Page(d, out)
        d.get(daemon.url)
        p.wait("the Shop section", lambda: p.q("#panel-shop").is_displayed(), 15)
        p.wait("this daemon's machine in the shop's machines",
               lambda: d.find_elements(By.CSS_SELECTOR, '#shop-machines tr[data-machine="w1"]'), 15)
        assert "acme" in p.text("#shop-name"), p.text("#shop-name")

        # Submit a program from the page's form.
        program = os.path.abspath(os.path.join(out, "shop-part.nc"))  # the browser wants an absolute path
        with open(program, "w") as f:
            f.write("G21\nG90\nG0 X1\nG1 X0 F600\n")
        p.q("#shop-file").send_keys(program)
        assert not p.q("#shop-tool").is_displayed(), "the cutter is asked for an STL only"
        p.click("#shop-submit-button")
        p.wait("the submission's confirmation", lambda: "is job #" in p.text("#shop-submit-status"), 15)
        row = '#shop-jobs tr.shop-job'

        def job_rows():
            """[id, status, text] of each job row, read at once (the view re-renders while it polls)."""
            return d.execute_script("return [...document.querySelectorAll(arguments[0])]"
                                    ".map((r) => [r.dataset.job, r.dataset.status, r.textContent])", row)

        def status_of(job):
            return next((st for j, st, _ in job_rows() if j == job), None)

        p.wait("the submitted job in the shop's queue, pending", lambda: [
            j for j, st, text in job_rows() if "shop-part.nc" in text and st == "pending"], 10)
        job = next(j for j, st, text in job_rows() if "shop-part.nc" in text)
        assert hub.sql(f"SELECT status || ' ' || submitted_by FROM shop.jobs WHERE id = {job}") == "pending pc_web"
        p.shot("shop-submitted")

        # Cancel it from its row.
        p.click(f'{row}[data-job="{job}"] button[data-act="cancel"]')
        p.wait("the job cancelled in the view", lambda: status_of(job) == "cancelled", 10)
        assert hub.sql(f"SELECT status FROM shop.jobs WHERE id = {job}") == "cancelled"
        assert not d.find_elements(By.CSS_SELECTOR, f'{row}[data-job="{job}"] button[data-act="cancel"]'), \
            "a cancelled job offers no Cancel"

        # Put it back: the operator's explicit act, here for any machine.
        p.click(f'{row}[data-job="{job}"] button[data-act="requeue-any"]')
        p.wait("the job pending again", lambda: status_of(job) == "pending", 10)
        assert hub.sql(f"SELECT status FROM shop.jobs WHERE id = {job}") == "pending"

        # A change on the hub is drawn from the `shop` frame alone: the page's
        # reads of the view are refused meanwhile, so nothing else can show it.
        d.execute_script("""
            window.__shopFetch = window.fetch;
            window.__blockedReads = 0;
            window.fetch = (u, ...a) => /\/shop\/(jobs|machines)(\?|$)/.test(String(u))
              ? (window.__blockedReads++, Promise.reject(new Error('blocked by the test')))
              : window.__shopFetch(u, ...a);""")
        hub.sql(f"UPDATE shop.jobs SET message = 'noted on the hub' WHERE id = {job}")
        p.wait("the hub's change drawn from the frame", lambda: any(
            j == job and "noted on the hub" in text for j, _, text in job_rows()), 10)
        d.execute_script("window.fetch = window.__shopFetch;")
        p.full_shot("shop-view")
        errors = [e for e in p.console_errors() if "favicon" not in e.get("message", "")]
        assert not errors, f"errors in the browser's console: {errors}"
    finally:
        daemon.stop()


def main():
    def extra(ap):
        ap.add_argument("--cli", default=os.environ.get("CNCSTREAM_CLI"), help="the cncstream binary (for shop init)")
        ap.add_argument("--pg-template", help="where PostgreSQL's initialised cluster is kept between runs"
                        " (default: shop-pg-template beside the output folder's test-output)")
    args = tp.page_test_args("web-shop", extra)
    if not tp.have_programs(("cncstreamd (--daemon)", args.daemon), ("cncstream (--cli)", args.cli)):
        return 1
    tp.fresh_output(args.output, (".png", ".log", ".nc"))

    def flow(d):
        template = args.pg_template or os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(args.output))),
                                                    "shop-pg-template")
        hub = TempHub(args.output, template)
        try:
            shop_flow(args, args.output, d, hub)
        finally:
            hub.stop()
    return tp.run_in_browser(args, flow)


if __name__ == "__main__":
    sys.exit(main())
