"""Every relative link in README.md and docs/**/*.md points to an existing file (and heading, for #anchors).

    python3 docs/check_links.py [REPOSITORY_ROOT]
"""
import pathlib, re, sys
ROOT = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[1]).resolve()
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
def slug(h):
    h = re.sub(r"[`*_]", "", h.strip().lower())
    return re.sub(r"[^\w\- ]", "", h).replace(" ", "-")
def anchors(path):
    out, fence = set(), False
    for line in path.read_text().splitlines():
        if line.startswith("```"):
            fence = not fence
        elif not fence and line.startswith("#"):
            out.add(slug(line.lstrip("#")))
    return out
bad, n = [], 0
for md in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
    text = re.sub(r"```.*?```", "", md.read_text(), flags=re.S)
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue
        n += 1
        file, _, frag = target.partition("#")
        dest = (md.parent / file).resolve() if file else md
        if not dest.exists():
            bad.append(f"{md.relative_to(ROOT)}: {target} (no such file)")
        elif frag and dest.is_file() and dest.suffix == ".md" and frag not in anchors(dest):
            bad.append(f"{md.relative_to(ROOT)}: {target} (no such heading)")
print(f"{n} relative links checked, {len(bad)} broken")
print("\n".join(bad))
sys.exit(1 if bad else 0)
