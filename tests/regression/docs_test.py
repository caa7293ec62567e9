#!/usr/bin/python3
"""The documentation against the repository and the binary.

    docs_test.py links ROOT            every image and relative link of README.md and docs/*.md
                                       exists (anchors too); every picture of docs/figures/ is
                                       made by scripts/paper_figures.sh, and the commands quoted
                                       under it are the ones the script runs
    docs_test.py cli ROOT VIBRO        docs/cli.md lists, per command, exactly the options that
                                       `vibro COMMAND --help` shows
    docs_test.py cpp ROOT EXAMPLE      docs/cpp.md shows examples/first.cpp and its real output

The truth is the file system, the script and the binary's own --help, never the docs themselves.
"""
import os
import re
import shlex
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402


def expect(ok, what):
    check(what, ok)

# Pages that other branches write; tolerated as missing until they are merged (then checked).
PENDING_PAGES = set()  # pages written on other branches, none now

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    h = heading.strip().lower()
    h = re.sub(r"[^\w\- ]", "", h)
    return h.replace(" ", "-")


def anchors(path):
    with open(path, encoding="utf-8") as f:
        return {slug(m.group(1)) for m in re.finditer(r"^#+\s+(.*)$", f.read(), re.M)}


def doc_files(root):
    files = [os.path.join(root, "README.md")]
    d = os.path.join(root, "docs")
    files += sorted(os.path.join(d, n) for n in os.listdir(d) if n.endswith(".md"))
    return files


def outside_code(text):
    """The text with fenced code blocks blanked (links inside code are not links)."""
    return re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)


def check_links(root):
    for path in doc_files(root):
        rel_doc = os.path.relpath(path, root)
        with open(path, encoding="utf-8") as f:
            text = outside_code(f.read())
        for target in LINK.findall(text):
            if re.match(r"^[a-z]+:", target):      # http:, https:, mailto:
                continue
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
            rel = os.path.relpath(dest, root)
            if rel.startswith(".."):
                expect(False, f"{rel_doc}: {target} points outside the repository")
                continue
            if not os.path.exists(dest):
                if rel in PENDING_PAGES:
                    print(f"note: {rel_doc} links {rel}, written on another branch (not yet here)")
                    continue
                expect(False, f"{rel_doc}: {target} does not exist")
                continue
            if anchor and dest.endswith(".md"):
                expect(anchor in anchors(dest), f"{rel_doc}: {target}: no heading with anchor #{anchor}")
        for ref in re.findall(r"\.\./shared|MODEL\.md|CONTRACT §|MODEL §", text):
            expect(False, f"{rel_doc}: refers to '{ref}', which is outside the repository")


def script_commands(script):
    """The vibro commands of paper_figures.sh, normalised as the docs quote them, and for each
    picture of docs/figures the plot command that made it."""
    with open(script, encoding="utf-8") as f:
        lines = f.read().replace("\\\n", " ").splitlines()

    def norm(tokens):
        out = []
        for t in tokens:
            t = t.replace("$S/", "data/scenes/").replace("$tmp/", "")
            out.append(t)
        return out
    commands, made_by, last_plot = [], {}, None
    for line in lines:
        line = line.strip()
        if line.startswith("run "):
            cmd = norm(shlex.split(line, posix=True)[1:])
            commands.append(cmd)
            if cmd[0] == "plot":
                last_plot = cmd
        elif line.startswith("fig "):
            name, panel = line.split()[1:3]
            cmd = ["plot", f"{name}.h5"]
            commands.append(cmd)
            made_by[f"{name}.png"] = cmd
        elif line.startswith("cp ") and "$out/" in line and last_plot is not None:
            name = os.path.basename(shlex.split(line)[-1].replace("$out/", ""))
            made_by[name] = last_plot
    return commands, made_by


def check_captions(root):
    script = os.path.join(root, "scripts", "paper_figures.sh")
    commands, made_by = script_commands(script)
    figdir = os.path.join(root, "docs", "figures")
    pngs = sorted(n for n in os.listdir(figdir) if n.endswith(".png"))
    for n in pngs:
        expect(n in made_by, f"docs/figures/{n} is not made by scripts/paper_figures.sh")
    for n in made_by:
        expect(n in pngs, f"scripts/paper_figures.sh makes docs/figures/{n}, which is not committed")
    shown = set()
    for path in doc_files(root):
        rel_doc = os.path.relpath(path, root)
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
        for i, line in enumerate(lines):
            for target in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", line):
                if "figures/" not in target:
                    continue
                name = os.path.basename(target)
                shown.add(name)
                # The caption's commands: the first code block after the picture, before the next
                # picture or heading. Pictures shown without commands (the README gallery) link
                # to docs/figures.md instead.
                block, j, inside = [], i + 1, False
                while j < len(lines):
                    l = lines[j]
                    if not inside and (l.startswith("#") or "![" in l):
                        break
                    if l.startswith("```"):
                        if inside:
                            break
                        inside = True
                    elif inside:
                        block.append(l)
                    j += 1
                quoted = []
                for l in "\n".join(block).replace("\\\n", " ").splitlines():
                    l = l.split("#")[0].strip()
                    if l.startswith("vibro "):
                        quoted.append(shlex.split(l)[1:])
                if not quoted:
                    expect(rel_doc == "README.md", f"{rel_doc}: {target} has no commands under it")
                    continue
                for q in quoted:
                    expect(q in commands, f"{rel_doc}: {target}: `vibro {' '.join(q)}` is not a command "
                          f"of scripts/paper_figures.sh")
                if name in made_by:
                    expect(made_by[name] in quoted, f"{rel_doc}: {target}: the script makes it with "
                          f"`vibro {' '.join(made_by[name])}`, which the caption does not quote")
    for n in pngs:
        expect(n in shown, f"docs/figures/{n} is shown nowhere in README.md or docs/")


HELP_OPTION = re.compile(r"^\s+(?:-\w,\s*)?(--[a-z][a-z0-9-]*)", re.M)


def check_cli(root, vibro):
    top = subprocess.run([vibro, "--help"], capture_output=True, text=True).stdout
    sub = re.search(r"^Subcommands:\n(.*)", top, re.S | re.M | re.I)
    expect(sub is not None, "vibro --help lists its subcommands")
    commands = re.findall(r"^\s+([a-z]+)\s", sub.group(1), re.M) if sub else []
    with open(os.path.join(root, "docs", "cli.md"), encoding="utf-8") as f:
        text = f.read()
    sections = dict(re.findall(r"^## `vibro ([a-z]+)`\n(.*?)(?=^## |\Z)", text, re.M | re.S))
    expect(set(sections) == set(commands),
          f"docs/cli.md has sections for {sorted(sections)}, vibro --help lists {sorted(commands)}")
    for c in commands:
        out = subprocess.run([vibro, c, "--help"], capture_output=True, text=True).stdout
        helped = set(HELP_OPTION.findall(out)) - {"--help"}
        section = sections.get(c, "")
        opt = r"(?<![\w-])(--[a-z][a-z0-9-]*)"
        # Documented: named in the first cell of an option table row or on an "Options:" line.
        rows = [l.split("|")[1] for l in section.splitlines() if l.startswith("| `--")]
        rows += [l for l in section.splitlines() if l.startswith("Options:")]
        documented = set(re.findall(opt, "\n".join(rows)))
        mentioned = set(re.findall(opt, section)) - {"--help"}
        expect(helped <= documented, f"docs/cli.md, vibro {c}: not documented: {sorted(helped - documented)}")
        expect(mentioned <= helped, f"docs/cli.md, vibro {c}: not in --help: {sorted(mentioned - helped)}")


def check_cpp(root, exe):
    """docs/cpp.md shows examples/first.cpp verbatim, and the output it quotes is the program's."""
    with open(os.path.join(root, "docs", "cpp.md"), encoding="utf-8") as f:
        text = f.read()
    blocks = re.findall(r"^```(\w*)\n(.*?)^```", text, re.M | re.S)
    code = [b for lang, b in blocks if lang == "cpp"]
    with open(os.path.join(root, "examples", "first.cpp"), encoding="utf-8") as f:
        source = f.read()
    expect(len(code) == 1 and code[0] == source, "docs/cpp.md shows examples/first.cpp as it is")
    p = subprocess.run([exe], capture_output=True, text=True, cwd=root)
    expect(p.returncode == 0, f"examples/first.cpp runs: {p.stderr}")
    quoted = [b for lang, b in blocks if lang == "" and b.startswith("t_end")]
    expect(len(quoted) == 1 and quoted[0] == p.stdout,
           f"docs/cpp.md quotes the example's output: {p.stdout!r}")


def main():
    what, root = sys.argv[1], sys.argv[2]
    if what == "links":
        check_links(root)
        check_captions(root)
    elif what == "cli":
        check_cli(root, sys.argv[3])
    elif what == "cpp":
        check_cpp(root, sys.argv[3])
    else:
        sys.exit(f"unknown check {what}")
    finish()


if __name__ == "__main__":
    main()
