"""Reports open in a real browser: every figure loads and the page raises no error.

Runs headless Chromium (Debian's ``chromium`` package, installed by ``.ci/run``); skips with a
message where it is absent. A check script is injected into a copy of the report; it records
script errors and failed resources from the start, and on ``load`` writes the number of images,
the broken ones and the errors into the page, which ``--dump-dom`` returns.
"""

import json
import re
import shutil
import subprocess

import pytest

from rczone.cli.main import main

BROWSER = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
pytestmark = [
    pytest.mark.slow,  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow
    pytest.mark.skipif(BROWSER is None, reason="headless Chromium not installed (apt install chromium)"),
]

HEAD = """<script>
window.__errors = [];
window.addEventListener('error', function (e) {
  window.__errors.push(String(e.message || (e.target && (e.target.src || e.target.href)) || 'error'));
}, true);
var __consoleError = console.error;
console.error = function () { window.__errors.push(Array.prototype.join.call(arguments, ' ')); __consoleError.apply(console, arguments); };
</script>"""
TAIL = """<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var broken = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); })
                   .map(function (i) { return i.alt || i.src.slice(0, 40); });
  var pre = document.createElement('pre');
  pre.id = 'rczone-check';
  pre.textContent = JSON.stringify({images: imgs.length, broken: broken, errors: window.__errors});
  document.body.appendChild(pre);
});
</script>"""


def check_in_browser(html: str, tmp_path) -> dict:
    """Load ``html`` in headless Chromium; return ``{"images", "broken", "errors"}``."""
    page = html.replace("<head>", "<head>" + HEAD, 1).replace("</body>", TAIL + "</body>", 1)
    path = tmp_path / "checked.html"
    path.write_text(page)
    cmd = [
        BROWSER,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--virtual-time-budget=10000",
        "--dump-dom",
        path.as_uri(),
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120).stdout
    m = re.search(r'<pre id="rczone-check">(.*?)</pre>', out, re.S)
    assert m, f"the check script did not run; browser output starts: {out[:300]!r}"
    return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    d = tmp_path_factory.mktemp("reports")
    assert main(["diagnose", "C", "--report", str(d / "diagnose")]) == 0
    assert main(["fit", "C", "--method", "ls", "--no-profiles", "--report", str(d / "fit")]) == 0
    return d


@pytest.mark.parametrize("name", ["diagnose", "fit"])
def test_every_figure_loads_and_no_errors(reports, tmp_path, name):
    html = (reports / name / "report.html").read_text()
    n_img = len(re.findall(r"<img ", html))
    assert n_img >= 1
    res = check_in_browser(html, tmp_path)
    assert res == {"images": n_img, "broken": [], "errors": []}


def test_a_broken_figure_and_a_script_error_are_caught(reports, tmp_path):
    html = (reports / "diagnose" / "report.html").read_text()
    bad = html.replace(
        "</body>",
        '<img alt="broken" src="data:image/png;base64,AAAA"><script>noSuchFunction();</script></body>',
        1,
    )
    res = check_in_browser(bad, tmp_path)
    assert res["broken"] == ["broken"]
    assert any("noSuchFunction" in e for e in res["errors"])
