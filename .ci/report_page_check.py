#!/usr/bin/env python3
"""The batch report page in a real browser (issue 40).

Runs `triwild batch` over a few bundled drawings, a fixture and a broken file,
opens OUTDIR/report.html from file:// in headless Chromium (driven over the
DevTools protocol on a pipe: the standard library only), and checks that

- the page loads with no console error, no uncaught exception and no failed
  resource load (Runtime / Log events);
- the gallery shows every file of report.jsonl exactly once;
- opening a file's section (its #f-N anchor) loads its preview and input
  drawing without error;

then saves screenshots of the page and of one file's section under
target/report-page/ (CI artifacts).

usage: report_page_check.py TRIWILD_BINARY CHROMIUM [OUT_DIR]
"""

import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


class Browser:
    """Chromium with --remote-debugging-pipe: requests on fd 3, replies on fd 4,
    each a JSON message ended by a NUL byte."""

    def __init__(self, chromium, profile):
        import fcntl

        to_r, self.to_w = os.pipe()
        self.from_r, from_w = os.pipe()
        # fds of 10 and up, so that the shell's redirections onto 3 and 4
        # below cannot overwrite one of them
        hi_r = fcntl.fcntl(to_r, fcntl.F_DUPFD, 10)
        hi_w = fcntl.fcntl(from_w, fcntl.F_DUPFD, 10)
        os.close(to_r)
        os.close(from_w)
        to_r, from_w = hi_r, hi_w
        self.proc = subprocess.Popen(
            ["bash", "-c", f'exec "$@" 3<&{to_r} 4>&{from_w} {to_r}<&- {from_w}>&-', "bash",
             chromium, *FLAGS, "--remote-debugging-pipe", f"--user-data-dir={profile}", "about:blank"],
            pass_fds=(to_r, from_w),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_r)
        os.close(from_w)
        self.buf = b""
        self.next_id = 0
        self.events = []

    def send(self, method, params=None, session=None, timeout=60):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.to_w, json.dumps(msg).encode() + b"\0")
        deadline = time.time() + timeout
        while time.time() < deadline:
            m = self.read(deadline)
            if m is None:
                break
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)
        raise TimeoutError(method)

    def read(self, deadline):
        import select

        while b"\0" not in self.buf:
            left = deadline - time.time()
            if left <= 0:
                return None
            r, _, _ = select.select([self.from_r], [], [], left)
            if not r:
                return None
            chunk = os.read(self.from_r, 1 << 20)
            if not chunk:
                return None
            self.buf += chunk
        line, self.buf = self.buf.split(b"\0", 1)
        return json.loads(line)

    def wait_event(self, method, timeout=60):
        deadline = time.time() + timeout
        for i, e in enumerate(self.events):
            if e.get("method") == method:
                return self.events.pop(i)
        while time.time() < deadline:
            m = self.read(deadline)
            if m is None:
                break
            if m.get("method") == method:
                return m
            self.events.append(m)
        raise TimeoutError(method)

    def drain(self, seconds):
        deadline = time.time() + seconds
        while True:
            m = self.read(deadline)
            if m is None:
                return
            self.events.append(m)

    def close(self):
        try:
            self.send("Browser.close", timeout=10)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def problems(events):
    """Console errors, exceptions and failed loads among the events."""
    out = []
    for e in events:
        m, p = e.get("method"), e.get("params", {})
        if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append("console: " + " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
        elif m == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            out.append("exception: " + d.get("text", "") + " " + str(d.get("exception", {}).get("description", "")))
        elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            en = p["entry"]
            out.append(f"log: {en.get('text')} {en.get('url', '')}")
    return out


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    exe, chromium = sys.argv[1], sys.argv[2]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    work = os.path.abspath(sys.argv[3] if len(sys.argv) > 3 else os.path.join(root, "target/report-page"))
    shutil.rmtree(work, ignore_errors=True)
    inp, out = os.path.join(work, "in"), os.path.join(work, "out")
    os.makedirs(os.path.join(inp, "broken"))
    for name in ["star-evenodd.svg", "ello.svg", "caffe.svg"]:
        shutil.copy(os.path.join(root, "data/svg", name), os.path.join(inp, name))
    os.makedirs(os.path.join(inp, "fixtures"))
    shutil.copy(os.path.join(root, "tests/fixtures/model-circle.svg"), os.path.join(inp, "fixtures"))
    open(os.path.join(inp, "broken", "empty.svg"), "w").close()
    t = time.time()
    r = subprocess.run([exe, "batch", inp, "-o", out, "-j", "2"], capture_output=True, text=True)
    print(f"batch: exit {r.returncode} in {time.time() - t:.1f} s")
    print(r.stdout.strip())
    if r.returncode not in (0, 1):
        print(r.stderr)
        return 1
    page = os.path.join(out, "report.html")
    rows = [json.loads(l) for l in open(os.path.join(out, "report.jsonl")) if l.strip()]
    files = sorted(r["file"] for r in rows)

    failures = []
    with tempfile.TemporaryDirectory(prefix="triwild-chromium-") as profile:
        b = Browser(chromium, profile)
        try:
            target = b.send("Target.createTarget", {"url": "about:blank"})["targetId"]
            s = b.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
            for dom in ["Runtime.enable", "Log.enable", "Page.enable"]:
                b.send(dom, session=s)
            b.send("Emulation.setDeviceMetricsOverride",
                   {"width": 1400, "height": 1800, "deviceScaleFactor": 1, "mobile": False}, session=s)
            b.send("Page.navigate", {"url": "file://" + page}, session=s)
            b.wait_event("Page.loadEventFired")
            b.drain(1.0)
            got = b.send("Runtime.evaluate", {
                "expression": "JSON.stringify(Array.from(document.querySelectorAll('#grid a.card')).map(c => c.getAttribute('data-file')))",
                "returnByValue": True}, session=s)["result"]["value"]
            shown = json.loads(got)
            if sorted(shown) != files:
                failures.append(f"gallery files {sorted(shown)} != report files {files}")
            if len(shown) != len(set(shown)):
                failures.append("a file appears twice in the gallery")
            thumbs = b.send("Runtime.evaluate", {
                "expression": "Array.from(document.querySelectorAll('#grid img.thumb')).filter(i => i.complete && i.naturalWidth > 0).length",
                "returnByValue": True}, session=s)["result"]["value"]
            ok = sum(1 for r in rows if r["status"] == "ok")
            if thumbs != ok:
                failures.append(f"{thumbs} thumbnails drawn for {ok} meshes")
            plots = b.send("Runtime.evaluate", {
                "expression": "document.querySelectorAll('#plots svg').length", "returnByValue": True},
                session=s)["result"]["value"]
            if plots < 7:
                failures.append(f"{plots} plots drawn, expected 7")
            shot = b.send("Page.captureScreenshot", {"format": "png", "captureBeyondViewport": True}, session=s)
            with open(os.path.join(work, "screenshot.png"), "wb") as f:
                f.write(base64.b64decode(shot["data"]))
            # sort the gallery by time, descending: the script must run
            b.send("Runtime.evaluate", {"expression":
                   "var s=document.getElementById('sort');s.value='wall';s.dispatchEvent(new Event('change'));"
                   "var d=document.getElementById('dir');d.value='desc';d.dispatchEvent(new Event('change'));"}, session=s)
            order = json.loads(b.send("Runtime.evaluate", {
                "expression": "JSON.stringify(Array.from(document.querySelectorAll('#grid a.card')).map(c => +c.getAttribute('data-wall')))",
                "returnByValue": True}, session=s)["result"]["value"])
            if order != sorted(order, reverse=True):
                failures.append(f"sorting by time failed: {order}")
            # one meshed file's section: preview and input load
            first_ok = next((i for i, r in enumerate(sorted(rows, key=lambda r: r["file"])) if r["status"] == "ok"), None)
            if first_ok is not None:
                b.send("Runtime.evaluate", {"expression": f"location.hash='#f-{first_ok}'"}, session=s)
                b.drain(2.0)
                loaded = b.send("Runtime.evaluate", {
                    "expression": f"Array.from(document.querySelectorAll('#f-{first_ok} .pics img')).map(i => i.complete && i.naturalWidth > 0)",
                    "returnByValue": True}, session=s)["result"]["value"]
                if loaded != [True, True]:
                    failures.append(f"file section f-{first_ok}: preview and input loaded {loaded}")
                shot = b.send("Page.captureScreenshot", {"format": "png"}, session=s)
                with open(os.path.join(work, "screenshot-file.png"), "wb") as f:
                    f.write(base64.b64decode(shot["data"]))
            b.drain(0.5)
            failures += problems(b.events)
        finally:
            b.close()
    size = os.path.getsize(page)
    print(f"report page: {page} ({size / 1e6:.2f} MB, {len(files)} files); screenshots in {work}")
    for f in failures:
        print("FAIL:", f)
    if failures:
        return 1
    print("report page check: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
