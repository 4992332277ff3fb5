#!/usr/bin/env python3
"""Browser test of the replay page (`urdyn view`, `simulate --html`), and screenshots.

Drives Debian's headless Chromium over the DevTools protocol on a pipe
(--remote-debugging-pipe: NUL-terminated JSON on file descriptors 3 and 4), with
the Python standard library only.

    view_check.py lamp [--bin-dir target/debug] [--out-dir DIR] [--update-docs]
        runs the lamp_drop example (which writes lamp_drop.csv and lamp_drop.html),
        opens the page from disk and checks that
        - it becomes ready (window.urdynViewer.ready) without a console error or
          an uncaught exception, and reports how long that took;
        - window.urdynViewer.times are the CSV's times (a subsample keeping the
          first and the last row);
        - linkPose(name) of every URDF link, at several of the page's times, equals
          `urdyn eval`'s link_poses of that CSV row's q (to 1e-6);
        - screenshots at the start and at the end are drawn (not blank) and differ;
        - the play button moves the slider on.
        --update-docs writes the end screenshot to docs/lamp_drop.png.

    view_check.py shot PAGE.html OUT.png [--time T] [--size WxH]
        a screenshot of a page at time T (default: its end).

    view_check.py page PAGE.html [--min-frames N]
        any replay page (e.g. one urdyn.write_html or sim.write_html wrote from
        Python): it becomes ready without a console error, holds at least N frames,
        draws (screenshots at the start and the end not blank), moves (they differ)
        and plays (the play button moves the slider on).

Exit status 0 when every check passes; 77 with a loud message when no Chromium is
installed (the caller decides whether that is a failure); 1 otherwise.
"""
import argparse
import base64
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SKIP = 77


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        p = shutil.which(name)
        if p:
            return p
    return None


class Browser:
    """A headless Chromium and one page session, over --remote-debugging-pipe."""

    def __init__(self, exe, size=(1000, 700)):
        self.user_dir = tempfile.mkdtemp(prefix="urdyn-chromium-")
        to_child_r, self.to_child = os.pipe()
        self.from_child, from_child_w = os.pipe()

        def fds():
            # fd 3: what the browser reads; fd 4: what it writes.
            a, b = os.dup(to_child_r), os.dup(from_child_w)
            os.dup2(a, 3)
            os.dup2(b, 4)

        args = [
            exe, "--headless", "--no-sandbox", "--remote-debugging-pipe",
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
            "--disable-quic", "--no-first-run", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--disable-extensions",
            "--disable-default-apps", "--mute-audio", "--hide-scrollbars",
            f"--window-size={size[0]},{size[1]}", f"--user-data-dir={self.user_dir}",
            "about:blank",
        ]
        self.log = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(args, preexec_fn=fds, close_fds=False,
                                     stdout=self.log, stderr=self.log)
        os.close(to_child_r)
        os.close(from_child_w)
        self.buf = b""
        self.next_id = 0
        self.events = []
        self.session = None
        targets = self.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        self.session = self.call("Target.attachToTarget",
                                 {"targetId": page["targetId"], "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.call(f"{domain}.enable")
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": size[0], "height": size[1], "deviceScaleFactor": 1, "mobile": False})

    def _read_message(self, deadline):
        while b"\0" not in self.buf:
            if time.monotonic() > deadline:
                raise TimeoutError("no answer from Chromium")
            chunk = os.read(self.from_child, 1 << 20)
            if not chunk:
                self.log.seek(0)
                raise RuntimeError("Chromium closed the pipe: " + self.log.read()[-2000:].decode(errors="replace"))
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, params=None, timeout=60):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if self.session and not method.startswith("Target."):
            msg["sessionId"] = self.session
        os.write(self.to_child, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            m = self._read_message(deadline)
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            if "method" in m:
                self.events.append(m)

    def evaluate(self, expr, timeout=60):
        r = self.call("Runtime.evaluate", {"expression": expr, "returnByValue": True,
                                           "awaitPromise": True}, timeout)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expr[:80]}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def errors(self):
        out = []
        for e in self.events:
            m, p = e["method"], e.get("params", {})
            if m == "Runtime.exceptionThrown":
                out.append("exception: " + json.dumps(p.get("exceptionDetails", {}))[:500])
            elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append("console.error: " + json.dumps(p.get("args", []))[:500])
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                out.append("log error: " + p["entry"].get("text", "")[:500])
        return out

    def open(self, path, timeout=30):
        """Navigates to a file and waits for window.urdynViewer.ready; returns the
        page's own ready time (ms since navigation) and the wall time (s)."""
        url = "file://" + os.path.abspath(path)
        t0 = time.monotonic()
        self.call("Page.navigate", {"url": url})
        deadline = t0 + timeout
        while time.monotonic() < deadline:
            if self.evaluate("!!(window.urdynViewer && window.urdynViewer.ready)"):
                return self.evaluate("window.urdynViewer.readyMs"), time.monotonic() - t0
            if self.errors():
                break
            time.sleep(0.02)
        raise RuntimeError(f"{path}: not ready after {timeout} s; errors: {self.errors()}")

    def screenshot(self):
        return base64.b64decode(self.call("Page.captureScreenshot", {"format": "png"})["data"])

    def close(self):
        try:
            self.call("Browser.close", timeout=5)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.user_dir, ignore_errors=True)


def png_pixels(data):
    """(width, height, rows of RGB tuples' bytes) of an 8-bit RGB/RGBA PNG."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, color = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and color in (2, 6), f"PNG depth {depth} colour type {color}"
            bpp = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pr) & 255
        rows.append(bytes(line[k] for j in range(w) for k in (bpp * j, bpp * j + 1, bpp * j + 2)))
        prev = line
    return w, h, rows


def drawn_fraction(rows, region=None):
    """Fraction of pixels in the scene area (above the control panel) that are
    neither the background nor the ground's near-grey: drawn robot pixels."""
    h = len(rows)
    top, bottom = (0, int(h * 0.7)) if region is None else region
    count = total = 0
    for y in range(top, bottom):
        r = rows[y]
        for x in range(0, len(r), 3 * 4):  # every 4th pixel
            total += 1
            R, G, B = r[x], r[x + 1], r[x + 2]
            if max(R, G, B) - min(R, G, B) > 12 or max(R, G, B) < 150:
                count += 1
    return count / max(total, 1)


def pixel_difference(a, b):
    diff = total = 0
    for ra, rb in zip(a, b):
        for x in range(0, min(len(ra), len(rb)), 3 * 2):
            total += 1
            if abs(ra[x] - rb[x]) + abs(ra[x + 1] - rb[x + 1]) + abs(ra[x + 2] - rb[x + 2]) > 30:
                diff += 1
    return diff / max(total, 1)


def read_csv(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f if line.strip()]
    return header, rows


def eval_link_poses(urdyn, urdf, header, rows, floating, tmp):
    """urdyn eval's link_poses of the given CSV rows (lists of cells)."""
    states = []
    for row in rows:
        cell = dict(zip(header, row))
        q = {h[2:]: float(cell[h]) for h in header if h.startswith("q:") and not h.startswith("q:base_")}
        st = {"q": q}
        if floating:
            st["base"] = {
                "position": [float(cell[f"q:base_{k}"]) for k in "xyz"],
                "orientation_xyzw": [float(cell[f"q:base_{k}"]) for k in ("qx", "qy", "qz", "qw")],
            }
        states.append(st)
    path = os.path.join(tmp, "states.json")
    with open(path, "w") as f:
        json.dump({"states": states}, f)
    cmd = [urdyn, "eval", urdf, "--states", path] + (["--floating-base"] if floating else [])
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return [r["link_poses"] for r in json.loads(out)["results"]]


def check_lamp(args):
    chromium = find_chromium()
    if not chromium:
        print("=" * 72 + "\nSKIPPED: the browser test of the replay page needs Chromium "
              "(apt-get install chromium); none is installed.\n" + "=" * 72, file=sys.stderr)
        return SKIP
    bin_dir = os.path.abspath(args.bin_dir)
    urdyn = os.path.join(bin_dir, "urdyn")
    example = os.path.join(bin_dir, "examples", "lamp_drop")
    out_dir = args.out_dir or tempfile.mkdtemp(prefix="urdyn-view-")
    os.makedirs(out_dir, exist_ok=True)
    subprocess.run([example, out_dir], check=True, stdout=subprocess.DEVNULL)
    page = os.path.join(out_dir, "lamp_drop.html")
    csv = os.path.join(out_dir, "lamp_drop.csv")
    urdf = os.path.join(ROOT, "assets", "lamp.urdf")
    failures = []
    size = os.path.getsize(page)
    print(f"page: {page}, {size} bytes ({size / 1e6:.3f} MB)")
    if size >= 1_000_000:
        failures.append(f"the lamp page is {size} bytes, not under 1 MB")
    with open(page, encoding="utf-8") as f:
        text = f.read()
    for needle in ("http://", "https://", "src=\"", "<link"):
        if needle in text:
            failures.append(f"the page contains {needle!r}: it must need no network and no other file")

    header, rows = read_csv(csv)
    csv_times = [float(r[0]) for r in rows]
    b = Browser(chromium)
    try:
        ready_ms, wall = b.open(page)
        print(f"ready: {ready_ms:.0f} ms after navigation (page clock), {wall:.2f} s wall")
        if ready_ms > 10000:
            failures.append(f"ready only after {ready_ms:.0f} ms")
        info = b.evaluate("({frames: urdynViewer.frames, duration: urdynViewer.duration, times: urdynViewer.times})")
        times = info["times"]
        if info["frames"] != len(times) or len(times) < 2:
            failures.append(f"frames {info['frames']} but {len(times)} times")
        if times[0] != csv_times[0] or times[-1] != csv_times[-1]:
            failures.append("the page's first and last times are not the CSV's first and last rows")
        index = {t: i for i, t in enumerate(csv_times)}
        missing = [t for t in times if t not in index]
        if missing:
            failures.append(f"{len(missing)} page times are no CSV row's time, e.g. {missing[:3]}")
        if abs(info["duration"] - (csv_times[-1] - csv_times[0])) > 1e-12:
            failures.append(f"duration {info['duration']}")
        picks = sorted({0, len(times) // 5, len(times) // 2, (4 * len(times)) // 5, len(times) - 1})
        chosen = [rows[index[times[k]]] for k in picks if times[k] in index]
        with tempfile.TemporaryDirectory() as tmp:
            ref = eval_link_poses(urdyn, urdf, header, chosen, True, tmp)
        worst = 0.0
        for k, want in zip(picks, ref):
            shown = b.evaluate(f"urdynViewer.seek({json.dumps(times[k])})")
            if shown != times[k]:
                failures.append(f"seek({times[k]}) showed {shown}")
            got = b.evaluate("Object.fromEntries(%s.map(n => [n, urdynViewer.linkPose(n)]))"
                             % json.dumps(sorted(want)))
            for name, pose in want.items():
                g = got.get(name)
                if g is None:
                    failures.append(f"linkPose({name!r}) is null")
                    continue
                d = max([abs(x - y) for x, y in zip(g["position"], pose["position"])] +
                        [abs(x - y) for gr, wr in zip(g["rotation"], pose["rotation"]) for x, y in zip(gr, wr)])
                worst = max(worst, d)
                if d > 1e-6:
                    failures.append(f"t = {times[k]}: linkPose({name!r}) differs from eval by {d:.3g}")
        print(f"linkPose vs eval link_poses: {len(picks)} times x {len(ref[0])} links, "
              f"largest difference {worst:.3g}")

        b.evaluate(f"urdynViewer.seek({json.dumps(times[0])})")
        first = b.screenshot()
        b.evaluate(f"urdynViewer.seek({json.dumps(times[-1])})")
        last = b.screenshot()
        _, _, pa = png_pixels(first)
        _, _, pb = png_pixels(last)
        fa, fb, diff = drawn_fraction(pa), drawn_fraction(pb), pixel_difference(pa, pb)
        print(f"screenshots: {fa:.1%} and {fb:.1%} of the scene drawn, {diff:.2%} of pixels differ")
        if fa < 0.005 or fb < 0.005:
            failures.append("a screenshot shows no robot (blank page?)")
        if diff < 0.002:
            failures.append("the start and end screenshots do not differ")
        # Playback: from the start, the play button moves the slider on.
        b.evaluate(f"urdynViewer.seek({json.dumps(times[0])}); document.getElementById('play').click()")
        moved, waited = slider_after_play(b)
        print(f"playback: slider at frame {moved} after {waited:.1f} s")
        if not moved > 0:
            failures.append("the play button did not move the slider")
        b.evaluate(f"urdynViewer.seek({json.dumps(times[-1])})")
        if args.update_docs:
            with open(os.path.join(ROOT, "docs", "lamp_drop.png"), "wb") as f:
                f.write(last)
        errors = b.errors()
        if errors:
            failures.extend(errors)
    finally:
        b.close()
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    print("browser test of the replay page: " + ("FAILED" if failures else "passed"))
    return 1 if failures else 0


def shot(args):
    chromium = find_chromium()
    if not chromium:
        print("no Chromium installed", file=sys.stderr)
        return SKIP
    w, h = (int(x) for x in args.size.split("x"))
    b = Browser(chromium, (w, h))
    try:
        ready_ms, wall = b.open(args.page)
        t = args.time if args.time is not None else b.evaluate("urdynViewer.times[urdynViewer.frames - 1]")
        b.evaluate(f"urdynViewer.seek({json.dumps(t)})")
        png = b.screenshot()
        with open(args.out, "wb") as f:
            f.write(png)
        errors = b.errors()
    finally:
        b.close()
    print(f"{args.page}: ready {ready_ms:.0f} ms (page clock), {wall:.2f} s wall; wrote {args.out}"
          + (f"; errors: {errors}" if errors else ""))
    return 1 if errors else 0


def check_page(args):
    chromium = find_chromium()
    if not chromium:
        print("no Chromium installed", file=sys.stderr)
        return SKIP
    failures = []
    b = Browser(chromium)
    try:
        ready_ms, wall = b.open(args.page)
        print(f"{args.page}: ready {ready_ms:.0f} ms (page clock), {wall:.2f} s wall")
        times = b.evaluate("Array.from(urdynViewer.times)")
        if len(times) < args.min_frames:
            failures.append(f"{len(times)} frames, expected at least {args.min_frames}")
        b.evaluate(f"urdynViewer.seek({json.dumps(times[0])})")
        first = b.screenshot()
        b.evaluate(f"urdynViewer.seek({json.dumps(times[-1])})")
        last = b.screenshot()
        _, _, pa = png_pixels(first)
        _, _, pb = png_pixels(last)
        fa, fb, diff = drawn_fraction(pa), drawn_fraction(pb), pixel_difference(pa, pb)
        print(f"screenshots: {fa:.1%} and {fb:.1%} of the scene drawn, {diff:.2%} of pixels differ")
        if fa < 0.005 or fb < 0.005:
            failures.append("a screenshot shows nothing drawn (blank page?)")
        if diff < 0.002:
            failures.append("the start and end screenshots do not differ")
        b.evaluate(f"urdynViewer.seek({json.dumps(times[0])}); document.getElementById('play').click()")
        moved, waited = slider_after_play(b)
        print(f"playback: slider at frame {moved} after {waited:.1f} s")
        if not moved > 0:
            failures.append("the play button did not move the slider")
        failures.extend(b.errors())
    finally:
        b.close()
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    print(f"browser test of {args.page}: " + ("FAILED" if failures else "passed"))
    return 1 if failures else 0



def slider_after_play(b, limit=10.0):
    """The slider's frame once playback has moved it, polled every 0.2 s from 0.6 s on
    (a loaded machine's software WebGL may take seconds to draw a mesh-heavy page's next
    frame); 0 if it has not moved within `limit` seconds. Returns (frame, seconds)."""
    t0 = time.monotonic()
    time.sleep(0.6)
    while True:
        moved = b.evaluate("+document.getElementById('slider').value")
        waited = time.monotonic() - t0
        if moved > 0 or waited >= limit:
            return moved, waited
        time.sleep(0.2)

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("lamp")
    target = os.environ.get("CARGO_TARGET_DIR") or os.path.join(ROOT, "target")
    a.add_argument("--bin-dir", default=os.path.join(target, "debug"))
    a.add_argument("--out-dir")
    a.add_argument("--update-docs", action="store_true")
    s = sub.add_parser("shot")
    s.add_argument("page")
    s.add_argument("out")
    s.add_argument("--time", type=float)
    s.add_argument("--size", default="800x600")
    p = sub.add_parser("page")
    p.add_argument("page")
    p.add_argument("--min-frames", type=int, default=2)
    args = ap.parse_args()
    return {"lamp": check_lamp, "shot": shot, "page": check_page}[args.cmd](args)


if __name__ == "__main__":
    sys.exit(main())
