"""The built documentation as a reader's browser shows it, offline (issue 41).

Reads ``docs/_build/html`` as ``python -m sphinx -b html docs docs/_build/html`` writes it
(``.ci/run`` builds the site, then runs this file again); without a build every test here is
skipped.  Every page is checked for what it loads (parsed, no browser): no script, stylesheet,
icon or picture from another host.  Then each page with formulas or code is opened in headless
Chromium with the network blocked (every host name unresolvable, a proxy that is not there),
in a window 1,280 px wide, with a small script appended that waits for MathJax and the fonts
and writes what it finds into the page: every formula typeset (a ``mjx-container`` in every
``.math`` element, no ``\\(``, ``\\[`` or ``$$`` left in the text) and no code block wider
than its box (``scrollWidth <= clientWidth + 1``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
from html import unescape
from html.parser import HTMLParser
from pathlib import Path

import pytest
from browser import CHROMIUM, COMMON_FLAGS, run_chromium

ROOT = Path(__file__).resolve().parent.parent
HTML = ROOT / "docs" / "_build" / "html"
pytestmark = pytest.mark.skipif(
    not (HTML / "index.html").is_file(),
    reason="the documentation is not built (python -m sphinx -b html docs docs/_build/html; "
    ".ci/run builds it, then runs this file)",
)
browser = pytest.mark.skipif(
    not os.access(CHROMIUM, os.X_OK),
    reason="Debian's chromium is not installed (/usr/bin/chromium); .ci/run installs it",
)
#: The reader's window [px].
WIDTH, HEIGHT = 1280, 900
FLAGS = [
    "--headless=new",
    *COMMON_FLAGS,
    f"--window-size={WIDTH},{HEIGHT}",
    # offline: no host name resolves, and the proxy every request would go through is absent
    "--host-resolver-rules=MAP * ~NOTFOUND",
    "--proxy-server=127.0.0.1:9",
    "--allow-file-access-from-files",
    "--virtual-time-budget=30000",
    "--run-all-compositor-stages-before-draw",
    "--enable-logging=stderr",
    "--v=0",
]
#: Appended to a page: once it has loaded, MathJax has typeset and the fonts are in, write
#: what the reader sees into ``#pound-probe``.
PROBE = """<script>
window.addEventListener("load", function () {
  var typeset = (window.MathJax && MathJax.startup && MathJax.startup.promise) ||
    Promise.resolve();
  Promise.all([typeset, document.fonts.ready]).then(function () {
    var wide = [];
    document.querySelectorAll("pre").forEach(function (pre) {
      if (pre.offsetParent !== null && pre.scrollWidth > pre.clientWidth + 1) {
        wide.push(pre.textContent.split("\\n")[0].slice(0, 60) + " (" + pre.scrollWidth +
          " px in " + pre.clientWidth + ")");
      }
    });
    var text = document.body.cloneNode(true);
    text.querySelectorAll("pre, code, script, style, mjx-container, #pound-probe")
      .forEach(function (node) { node.remove(); });
    var raw = text.textContent.match(/\\\\\\(|\\\\\\[|\\$\\$/g) || [];
    var out = document.createElement("div");
    out.id = "pound-probe";
    out.setAttribute("data-found", JSON.stringify({
      width: window.innerWidth,
      math: document.querySelectorAll(".math").length,
      typeset: document.querySelectorAll(".math mjx-container").length,
      raw: raw.length,
      wide: wide,
      pre: document.querySelectorAll("pre").length
    }));
    document.body.appendChild(out);
  });
});
</script>"""


class _Loads(HTMLParser):
    """What a page loads: ``(tag, attribute, value)`` of its scripts, stylesheets, icons,
    pictures and frames, and the ``url(...)`` of its inline styles."""

    ATTRS = {
        "script": ("src",),
        "link": ("href",),
        "img": ("src", "srcset"),
        "source": ("src", "srcset"),
        "iframe": ("src",),
        "embed": ("src",),
        "object": ("data",),
        "video": ("src", "poster"),
        "audio": ("src",),
        "input": ("src",),
    }

    def __init__(self):
        super().__init__()
        self.loads = []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if value and name in self.ATTRS.get(tag, ()):
                self.loads.append((tag, name, value))
            if value and name == "style":
                self.loads += [(tag, "style", url) for url in _css_urls(value)]


def _css_urls(text: str) -> list[str]:
    return [u.strip("'\" ") for u in re.findall(r"url\(([^)]*)\)", text)] + re.findall(
        r"@import\s+[\"']([^\"']+)", text
    )


def _external(value: str) -> bool:
    """Whether a reference leaves the site: a scheme other than data, or a host (``//``)."""
    first = value.split(",")[0].strip().split(" ")[0]  # a srcset's first candidate
    return bool(re.match(r"^(//|[a-zA-Z][a-zA-Z0-9+.-]*:)", first)) and not first.startswith(
        "data:"
    )


def _pages() -> list[Path]:
    return sorted(p for p in HTML.rglob("*.html") if "_static" not in p.parts)


def test_every_page_and_stylesheet_loads_only_the_site_s_own_files():
    pages = _pages()
    assert len(pages) >= 15  # the guide, the tutorials, the reference
    seen = 0
    for page in pages:
        parser = _Loads()
        parser.feed(page.read_text(encoding="utf-8"))
        seen += len(parser.loads)
        external = [load for load in parser.loads if _external(load[2])]
        assert not external, (page.relative_to(HTML), external)
        for tag, name, value in parser.loads:  # and each file it names is there
            if name != "style" and not value.startswith("data:"):
                target = (page.parent / value.split("#")[0].split("?")[0]).resolve()
                assert target.exists(), (page.relative_to(HTML), tag, value)
    assert seen > 10 * len(pages)
    for sheet in HTML.joinpath("_static").rglob("*.css"):
        external = [u for u in _css_urls(sheet.read_text(encoding="utf-8")) if _external(u)]
        assert not external, (sheet.relative_to(HTML), external)
    # the check itself: a CDN script is caught
    assert _external("https://cdn.jsdelivr.net/npm/mathjax@3/es5/tex-chtml.js")
    assert _external("//cdn.example.org/x.js") and not _external("_static/mathjax/tex-chtml.js")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """A copy of the built site, where probe pages can be written beside the real ones."""
    copy = tmp_path_factory.mktemp("docs") / "html"
    shutil.copytree(HTML, copy)
    return copy


def _look(site: Path, page: Path, tmp_path: Path, html: str | None = None) -> dict:
    """What the probe finds on ``page`` of the copied ``site`` in the offline browser."""
    text = page.read_text(encoding="utf-8") if html is None else html
    probe = page.with_name(f"probe-{page.name}")
    probe.write_text(text.replace("</body>", PROBE + "</body>"), encoding="utf-8")
    run = run_chromium(tmp_path, FLAGS, "--dump-dom", probe.as_uri(), timeout=120)
    probe.unlink()
    assert run.returncode == 0, run.stderr[-2000:]
    found = re.search(r'id="pound-probe" data-found="([^"]*)"', run.stdout)
    assert found, (page.relative_to(site), run.stdout[-500:], run.stderr[-1500:])
    return json.loads(unescape(found.group(1)))


def _with_math_or_code() -> list[Path]:
    return [
        p
        for p in _pages()
        if 'class="math' in (text := p.read_text(encoding="utf-8")) or "<pre" in text
    ]


@browser
@pytest.mark.parametrize(
    "name", [str(p.relative_to(HTML)) for p in _with_math_or_code()] or ["index.html"]
)
def test_page_shows_its_formulas_and_code_offline_at_1280_px(name, site, tmp_path):
    found = _look(site, site / name, tmp_path)
    assert found["width"] == WIDTH
    # every formula typeset by the site's own MathJax, none left as TeX
    assert found["typeset"] == found["math"], found
    assert found["raw"] == 0, found
    # no code block scrolls sideways
    assert found["wide"] == [], found["wide"]


@browser
def test_the_probe_sees_a_formula_left_as_tex(site, tmp_path):
    """The check can fail: the contact page with MathJax from a CDN (blocked) shows TeX."""
    page = site / "contact.html"
    text = page.read_text(encoding="utf-8")
    assert 'class="math' in text and "_static/mathjax/" in text
    cdn = re.sub(r'src="[^"]*_static/mathjax/', 'src="https://cdn.jsdelivr.net/npm/mathjax@3/es5/',
                 text)  # fmt: skip
    found = _look(site, page, tmp_path, cdn)
    assert found["math"] > 10 and found["typeset"] == 0 and found["raw"] > 10, found
    # and a code block wider than its box is seen
    wide = text.replace("</body>", "<pre>" + "x" * 400 + "</pre></body>")
    assert len(_look(site, page, tmp_path, wide)["wide"]) == 1
