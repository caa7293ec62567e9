#!/usr/bin/python3
"""The documentation against the repository and the binary.

    docs_test.py links ROOT            every image and relative link of README.md and docs/*.md
                                       exists (anchors too); every picture of docs/figures/ is
                                       made by scripts/paper_figures.sh, and the commands quoted
                                       under it are the ones the script runs
    docs_test.py cli ROOT VIBRO        docs/cli.md lists, per command, exactly the options that
                                       `vibro COMMAND --help` shows
    docs_test.py cpp ROOT EXAMPLE      docs/cpp.md shows examples/first.cpp and its real output,
                                       and the find_package recipe tests/consumer builds
    docs_test.py output ROOT VIBRO     every command of README.md and docs/*.md shown with its
                                       output prints that output (rules in check_outputs)

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


def check_titles(root):
    """Every scene of data/scenes and data/benchmarks says in its title only what its keys hold:
    r = …, omega (ω) = …, f = … and x0 = … against stop.restitution, excitation.frequency,
    excitation.amplitude and stop.position; "preload" needs x0 > 0 and "clearance" x0 < 0. A
    benchmark's stored run (NAME.h5) carries the same title."""
    import glob
    import tomllib
    import h5py
    keys = {"r": ("stop", "restitution"), "omega": ("excitation", "frequency"), "ω": ("excitation", "frequency"),
            "f": ("excitation", "amplitude"), "x0": ("stop", "position")}
    paths = sorted(glob.glob(os.path.join(root, "data", "scenes", "**", "*.toml"), recursive=True) +
                   glob.glob(os.path.join(root, "data", "benchmarks", "*.toml")))
    claims = 0
    for path in paths:
        rel = os.path.relpath(path, root)
        with open(path, "rb") as f:
            scene = tomllib.load(f)
        title = scene.get("title", "")
        contacts = scene.get("contact", [])
        for sym, value in re.findall(r"(?<![\w.])(r|omega|ω|f|x0)\s*=\s*([-+]?[0-9.]+(?:[eE][-+]?\d+)?)", title):
            table, key = keys[sym]
            if table == "stop" and contacts:
                # A [[contact]] scene: the title's r (or x0) is every contact's restitution (or position).
                actual = [c.get(key) for c in contacts]
                claims += 1
                expect(all(a is not None and abs(float(value) - a) <= 1e-9 * max(1.0, abs(a)) for a in actual),
                       f"{rel}: the title says {sym} = {value}, contact[].{key} are {actual}")
                continue
            actual = scene.get(table, {}).get(key)
            claims += 1
            expect(actual is not None and abs(float(value) - actual) <= 1e-9 * max(1.0, abs(actual)),
                   f"{rel}: the title says {sym} = {value}, {table}.{key} is {actual}")
        x0 = scene.get("stop", {}).get("position")
        # A contact's gap at the origin: position < 0 below (clearance), position > 0 above (clearance).
        opens = [(-1 if c.get("side", "below") == "below" else 1) * c["position"] > 0 for c in contacts
                 if "position" in c]
        if "preload" in title:
            expect((x0 is not None and x0 > 0) or (opens and not all(opens)),
                   f"{rel}: the title says preload, stop.position is {x0}, contacts open at 0: {opens}")
        if "clearance" in title:
            expect((x0 is not None and x0 < 0) or (opens and any(opens)),
                   f"{rel}: the title says clearance, stop.position is {x0}, contacts open at 0: {opens}")
        stored = os.path.splitext(path)[0] + ".h5"
        if "benchmarks" in rel and os.path.exists(stored):
            with h5py.File(stored, "r") as f:
                text = f.attrs["scene"]
            text = text.decode() if isinstance(text, bytes) else text
            expect(tomllib.loads(text).get("title") == title, f"{os.path.relpath(stored, root)}: its stored scene's "
                   f"title is not {rel}'s")
    expect(len(paths) >= 20 and claims >= 40, f"titles checked: {len(paths)} scenes, {claims} claims")


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
    # The find_package recipe is the consumer project's, which consumer.install builds against an
    # installed prefix: every CMake command of the recipe, with the consumer's names.
    with open(os.path.join(root, "tests", "consumer", "CMakeLists.txt"), encoding="utf-8") as f:
        consumer = [l.strip() for l in f.read().replace("release_phase", "my_tool").replace(
            "vibro_consumer", "my_tool").splitlines() if l.strip() and not l.startswith("#")]
    recipes = [b for lang, b in blocks if lang == "cmake" and "find_package" in b]
    recipe = [l.split("#")[0].strip() for l in recipes[0].splitlines()] if recipes else []
    expect(len(recipes) == 1 and [l for l in recipe if l] == consumer,
           f"docs/cpp.md shows the find_package recipe of tests/consumer/CMakeLists.txt: {recipe} vs {consumer}")


# --- docs_test.py output -------------------------------------------------------------------
# Three ways a page shows what a command prints (fenced blocks):
#  A. a transcript: a block whose first line starts with "$ ". Each "$ " line (with its "\"
#     continuation lines) is a command, run by bash; the lines up to the next "$ " line are what
#     it prints (stdout and stderr, as a terminal shows them). "$ echo $?" prints the previous
#     command's exit status.
#  B. a ```sh block holding exactly one `build/vibro ...` or `vibro ...` command, followed (blank
#     lines between at most) by a plain ``` block: that command's output.
#  C. a plain ``` block after the line `<!-- output of: COMMAND -->`.
# A block whose info string says `file=NAME` (```toml file=bad.toml) is written to NAME first, for
# the commands after it. `<!-- docs-output: skip REASON -->` before a block leaves it out (a hand
# edit between commands); the reason is printed.
# Comparison: the shown lines are the printed ones, whole and in order; lines may be left out only
# where a line "…" (or "...") marks the elision (one or more lines), never changed. Numbers are compared as written, except those that legitimately vary: a
# number followed by a time unit (s, ms, µs: timings) matches any number, and numbers below 1e-12
# in magnitude on both sides (rounding residue: Newton residuals, errors at rounding level) match.
# All commands of a page run in one scratch directory holding links to data/, scripts/ and
# build/vibro, in page order.

NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
TIMING = re.compile(r"\s*(?:s|ms|µs)\b")


def split_numbers(line):
    """(texts, numbers): the line's text between numbers, and each number with whether a time
    unit follows it."""
    texts, numbers, pos = [], [], 0
    for m in NUMBER.finditer(line):
        # A number glued to letters or underscores is part of a word (fig08, x_0, 1e-6T): text.
        if m.start() > 0 and (line[m.start() - 1].isalpha() or line[m.start() - 1] in "_."):
            continue
        texts.append(line[pos:m.start()])
        numbers.append((m.group(0), TIMING.match(line, m.end()) is not None))
        pos = m.end()
    texts.append(line[pos:])
    return texts, numbers


def same_line(shown, printed):
    st, sn = split_numbers(shown.rstrip())
    pt, pn = split_numbers(printed.rstrip())
    if st != pt or len(sn) != len(pn):
        return False
    for (a, timing), (b, _) in zip(sn, pn):
        if a == b or timing:
            continue
        try:
            x, y = float(a), float(b)
        except ValueError:
            return False
        if not (abs(x) < 1e-12 and abs(y) < 1e-12):
            return False
    return True


ELISION = ("...", "…")


def shown_in(shown_lines, printed_lines):
    """None when the shown lines are the printed ones, whole: line for line, except that a line
    "…" (or "...") stands for one or more printed lines deliberately left out. Else what differs:
    the first shown line that is not printed where it stands, or the printed lines the page does
    not show. Blank lines at the end of either are ignored."""
    def trim(v):
        v = list(v)
        while v and not v[-1].strip():
            v.pop()
        return v
    shown, printed = trim(shown_lines), trim(printed_lines)
    from functools import lru_cache

    @lru_cache(maxsize=None)
    def match(i, j):
        if i == len(shown):
            return j == len(printed)
        if shown[i].strip() in ELISION:
            return any(match(i + 1, k) for k in range(j + 1, len(printed) + 1))
        return j < len(printed) and same_line(shown[i], printed[j]) and match(i + 1, j + 1)
    if match(0, 0):
        return None
    # Where it goes wrong: the longest run of shown lines that matches from the start.
    i = j = 0
    while i < len(shown):
        if shown[i].strip() in ELISION:
            k = next((k for k in range(j + 1, len(printed) + 1) if match(i + 1, k)), None)
            if k is None:
                nxt = shown[i + 1] if i + 1 < len(shown) else None
                return nxt if nxt is not None else "… (nothing printed to elide)"
            return None  # unreachable: match(0, 0) would be true
        if j < len(printed) and same_line(shown[i], printed[j]):
            i, j = i + 1, j + 1
            continue
        return shown[i]
    return f"(not shown: {printed[j]!r}{' and more' if j + 1 < len(printed) else ''})"


def output_examples(path):
    """The examples of a page, in order: ("file", name, text), ("run", [(command, shown lines)]),
    ("skip", reason)."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    blocks, i = [], 0
    while i < len(lines):
        m = re.match(r"^```(.*)$", lines[i])
        if not m:
            i += 1
            continue
        j = i + 1
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        before = next((lines[k] for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        blocks.append({"info": m.group(1).strip(), "body": lines[i + 1:j], "start": i, "end": j,
                       "before": before})
        i = j + 1
    out = []
    for n, b in enumerate(blocks):
        skip = re.match(r"^<!-- docs-output: skip (.*) -->$", b["before"])
        named = re.search(r"\bfile=(\S+)", b["info"])
        if named:
            out.append(("file", named.group(1), "\n".join(b["body"]) + "\n"))
            continue
        body = b["body"]
        if body and body[0].startswith("$ "):
            if skip:
                out.append(("skip", f"{os.path.basename(path)}:{b['start'] + 1}: {skip.group(1)}"))
                continue
            steps, k = [], 0
            while k < len(body):
                cmd = body[k][2:]
                while cmd.endswith("\\") and k + 1 < len(body):
                    k += 1
                    cmd = cmd[:-1] + " " + body[k].strip()
                k += 1
                shown = []
                while k < len(body) and not body[k].startswith("$ "):
                    shown.append(body[k])
                    k += 1
                steps.append((cmd, shown))
            out.append(("run", b["start"] + 1, steps))
            continue
        marker = re.match(r"^<!-- output of: (.*) -->$", b["before"])
        if b["info"] == "" and marker:
            out.append(("run", b["start"] + 1, [(marker.group(1), body)]))
            continue
        if b["info"] == "" and n > 0 and blocks[n - 1]["info"] == "sh" and \
                all(not l.strip() for l in lines[blocks[n - 1]["end"] + 1:b["start"]]):
            cmds = [c.split("#")[0].strip() for c in "\n".join(blocks[n - 1]["body"]).replace("\\\n", " ").splitlines()]
            cmds = [c for c in cmds if c]
            if len(cmds) == 1 and re.match(r"^(build/)?vibro ", cmds[0]):
                out.append(("run", b["start"] + 1, [(cmds[0], body)]))
    return out


def check_outputs(root, vibro):
    import tempfile
    runs = skipped = 0
    mutation_checked = dropped_checked = False
    for path in doc_files(root):
        rel_doc = os.path.relpath(path, root)
        examples = output_examples(path)
        if not examples:
            continue
        with tempfile.TemporaryDirectory() as work:
            for name in ("data", "scripts"):
                os.symlink(os.path.join(os.path.abspath(root), name), os.path.join(work, name))
            os.mkdir(os.path.join(work, "build"))
            os.symlink(os.path.abspath(vibro), os.path.join(work, "build", "vibro"))
            env = dict(os.environ, PATH=os.path.join(work, "build") + os.pathsep + os.environ.get("PATH", ""))
            for ex in examples:
                if ex[0] == "file":
                    with open(os.path.join(work, ex[1]), "w", encoding="utf-8") as f:
                        f.write(ex[2])
                    continue
                if ex[0] == "skip":
                    skipped += 1
                    print(f"note: not run: {ex[1]}")
                    continue
                _, line, steps = ex
                rc = 0
                for cmd, shown in steps:
                    if cmd.strip() == "echo $?":
                        printed = [str(rc)]
                    else:
                        p = subprocess.run(["bash", "-c", cmd], cwd=work, env=env, capture_output=True,
                                           text=True, timeout=600)
                        rc = p.returncode
                        printed = (p.stdout + p.stderr).splitlines()
                    runs += 1
                    missing = shown_in(shown, printed)
                    check(f"{rel_doc}:{line}: `{cmd}` prints what the page shows", missing is None,
                          f"differs at: {missing!r}\nprinted:\n" + "\n".join(printed))
                    # The comparison can fail: the shown output with one digit changed must not pass.
                    if missing is None and not mutation_checked:
                        for n, l in enumerate(shown):
                            m = re.search(r"\d", l)
                            if m and l.strip() not in ("...", "…"):
                                d = "1" if l[m.start()] != "1" else "2"
                                changed = shown[:n] + [l[:m.start()] + d + l[m.end():]] + shown[n + 1:]
                                check(f"{rel_doc}:{line}: a changed digit is seen", shown_in(changed, printed) is not None,
                                      changed[n])
                                mutation_checked = True
                                break
                    # ... and so must the shown output with one printed line left out unmarked.
                    kept = [n for n, l in enumerate(shown) if l.strip() and l.strip() not in ELISION]
                    if missing is None and not dropped_checked and len(kept) >= 2:
                        short = shown[:kept[-2]] + shown[kept[-2] + 1:]
                        check(f"{rel_doc}:{line}: a line left out without '…' is seen",
                              shown_in(short, printed) is not None, shown[kept[-2]])
                        dropped_checked = True
    check(f"the docs show commands with their output ({runs} commands run, {skipped} blocks skipped)",
          runs >= 10 and mutation_checked and dropped_checked, runs)


def check_comparison():
    """The whole-transcript comparison on made-up transcripts whose verdict is known."""
    printed = ["status ok", "t_end 1.5 (2 periods)", "events 3 impacts", "output f.h5 (0.01 s writing)"]
    cases = [(printed, True), (printed[:1] + ["…"] + printed[3:], True), (["…"], True),
             (printed[:1] + ["..."] + printed[2:], True), (printed + [""], True),
             (printed[:2] + printed[3:], False),          # a line left out, unmarked
             (printed[:3], False),                        # the last line left out, unmarked
             (printed[1:], False),                        # the first line left out, unmarked
             (printed[:2] + ["…"] + printed[2:], False),  # "…" must stand for at least one line
             (printed + ["…"], False),
             (printed[:1] + ["events 3 impacts", "…"], False),  # out of order
             (["status ok", "t_end 1.6 (2 periods)", "…"], False)]
    for shown, passes in cases:
        got = shown_in(shown, printed) is None
        check(f"the comparison {'accepts' if passes else 'refuses'} {shown!r}", got == passes, shown_in(shown, printed))


def main():
    what, root = sys.argv[1], sys.argv[2]
    if what == "links":
        check_links(root)
        check_captions(root)
        check_titles(root)
    elif what == "cli":
        check_cli(root, sys.argv[3])
    elif what == "output":
        check_comparison()
        check_outputs(root, sys.argv[3])
    elif what == "cpp":
        check_cpp(root, sys.argv[3])
    else:
        sys.exit(f"unknown check {what}")
    finish()


if __name__ == "__main__":
    main()
