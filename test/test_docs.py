"""The docs say what the program has (issue 44 item 4, issue 39 finding 20):
docs/SCENE.md's "Features" list is the program's feature list, and every
feature in it is named in the README's "Features and known limits", in the
man page's DESCRIPTION and in --help; no sentence of the README's list denies
one ("No area lights ...", "... are ignored"); every section of SCENE.md is
named by a feature (so a section a new renderer adds, an environment light or
emission, forces a feature here, and the feature forces the README, the man
page and --help to follow); and the README's results paragraph stays short,
its figures in docs/results."""
import os
import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))

# SCENE.md's sections that describe the format, not a feature of a scene.
STRUCTURAL = {"rtcl scene files (format versions 1 and 2)", "Features", "Fields", "Errors"}


def section(text, heading, level="##"):
    """The text under `heading` up to the next heading of its level or above."""
    start = text.index(f"{level} {heading}\n")
    rest = text[start + len(level) + len(heading) + 2:]
    end = re.search(rf"^#{{1,{len(level)}}} ", rest, re.M)
    return rest[:end.start()] if end else rest


def plain(text):
    """Lower case, dashes and hyphens as spaces, one space between words,
    roff's escapes and fonts undone: so that "Blinn–Phong", "Blinn-Phong" and
    "Blinn\\(enPhong" compare equal, as do "thin-lens" and "thin lens"."""
    text = re.sub(r"^\.[A-Z]+ ?", "", text, flags=re.M)  # roff requests (.B, .IR, ...)
    text = text.replace("\\(en", "-").replace("\\(em", "-").replace("\\-", "-")
    text = re.sub(r"\\f[BIRP]", "", text)
    text = text.replace("*", "").replace("`", "").replace('"', "")
    text = re.sub(r"[-–—]", " ", text.lower())
    return " ".join(text.split())


def features():
    text = section((ROOT / "docs" / "SCENE.md").read_text(), "Features")
    return [" ".join(term.split()) for term in re.findall(r"\*\*(.+?)\*\*", text, re.S)]


def test_scene_md_lists_features():
    names = features()
    assert len(names) >= 15, names
    for expected in ("sphere lights", "soft shadows", "thin lens", "depth of field",
                     "textures", "own materials", "directional lights", "model file"):
        assert expected in names


def test_every_section_of_scene_md_is_named_by_a_feature():
    text = (ROOT / "docs" / "SCENE.md").read_text()
    listed = " ".join(section(text, "Features").split())
    headings = [h.strip() for h in re.findall(r"^#{1,4} (.+)$", text, re.M)]
    unnamed = [h for h in headings if h not in STRUCTURAL and f'"{h}"' not in listed]
    assert unnamed == [], f"SCENE.md sections no feature names: {unnamed}"


def readme_features():
    return section((ROOT / "README.md").read_text(), "Features and known limits")


def man_description():
    text = (ROOT / "docs" / "rtcl.1").read_text()
    start = text.index(".SH DESCRIPTION\n")
    return text[start:text.index(".SH ", start + 1)]


def help_text():
    return subprocess.run([RTCL, "--help"], capture_output=True, text=True,
                          timeout=60).stdout


@pytest.mark.parametrize("where", ["README", "man page DESCRIPTION", "--help"])
def test_every_feature_is_named_in_the_readme_the_man_page_and_help(where):
    text = plain({"README": readme_features, "man page DESCRIPTION": man_description,
                  "--help": help_text}[where]())
    missing = [name for name in features() if plain(name) not in text]
    assert missing == [], f"{where} does not name these features of SCENE.md: {missing}"


def test_the_readme_denies_no_feature():
    sentences = re.split(r"(?<=[.;:])\s+|\n\s*\*", readme_features())
    for name in features():
        for sentence in sentences:
            s = plain(sentence)
            if plain(name) not in s:
                continue
            assert not re.search(rf"\bno\b[^.]*\b{re.escape(plain(name))}\b", s) and \
                "ignored" not in s, f"the README denies {name!r}: {sentence!r}"


def test_the_readme_results_paragraph_is_short_and_points_to_the_tables():
    results = section((ROOT / "README.md").read_text(), "Results")
    assert len(results.split()) <= 120, len(results.split())
    assert "docs/results/README.md" in results
    short = section((ROOT / "docs" / "results" / "README.md").read_text(), "In short")
    assert short.count("\n|") >= 8  # the figures, as a table
