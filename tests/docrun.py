"""Find and run the code blocks of the project's Markdown files (used by test_doc_blocks.py).

A block is a fenced block; its kind comes from its language:

- ``python``: executed (each block in a fresh namespace, one interpreter per file, in a
  copy of the repository); a ``print(...)`` whose line ends in a comment that is a
  Python literal (``print(volume)  # 1.0``) must print that literal;
- ``sh`` / ``bash``: each command (``\\`` continues a line) runs in bash after
  ``source .venv/bin/activate``, as the README says, with standard input empty, and must
  exit 0; ``make X`` runs with the virtual environment taken as installed (the copy shares
  this checkout's ``.venv``), and ``make test`` (the suite itself) is not run again;
- ``wcl``: a script of the command language, run with ``workcell run``; a first line
  ``# NAME.wcl ...`` saves it under that name first (the text around it refers to it);
- ``json``: one JSON document, or one per line;
- ``text``: literal text (layouts, diagrams, sample output), not run;
- no language: a shell transcript (lines starting ``workcell> ``), replayed with
  ``workcell shell --echo`` and compared, or a protocol exchange (``S:``/``C:`` lines),
  replayed against a server and compared; anything else must say ``text``.

A block whose first line starts with ``# not run here:`` is not run with the others; the
rest of that line says why and which test covers it another way (a block that starts a
server is run by ``test_marked_server_blocks``).
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MARK = "# not run here:"
PROMPT = "workcell> "
_FENCE = re.compile(r"^```([\w-]*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)
_LANGS = {
    "python": "python",
    "sh": "sh",
    "bash": "sh",
    "wcl": "wcl",
    "json": "json",
    "text": "text",
}


def doc_files() -> list[str]:
    """README.md and every docs/*.md, relative to the repository."""
    return ["README.md", *sorted(f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md"))]


@dataclass(frozen=True)
class Block:
    """A fenced block of ``file`` starting at ``line`` (1-based, the fence)."""

    file: str
    line: int
    lang: str
    text: str

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"

    @property
    def marked(self) -> str | None:
        """The reason after ``# not run here:``, or None for a block that runs."""
        first = self.text.splitlines()[0] if self.text.strip() else ""
        return first[len(MARK) :].strip() if first.startswith(MARK) else None

    @property
    def kind(self) -> str:
        if self.lang in _LANGS:
            return _LANGS[self.lang]
        if self.lang:
            return "unknown"
        lines = self.text.splitlines()
        if lines and lines[0].startswith(PROMPT):
            return "transcript"
        if lines and all(ln.startswith(("S: ", "C: ")) for ln in lines):
            return "exchange"
        return "unknown"


def blocks(file: str) -> list[Block]:
    """The fenced blocks of ``file`` (relative to the repository), in order."""
    text = (ROOT / file).read_text(encoding="utf-8")
    return [
        Block(file, text.count("\n", 0, m.start()) + 1, m.group(1), m.group(2))
        for m in _FENCE.finditer(text)
    ]


def commands(text: str) -> list[str]:
    """The commands of a shell block: comments and blank lines dropped, ``\\`` joined."""
    out, cur = [], ""
    for raw in text.splitlines():
        line = raw.rstrip()
        if not cur and (not line.strip() or line.lstrip().startswith("#")):
            continue
        if line.endswith("\\"):
            cur += line[:-1] + " "
            continue
        out.append(cur + line)
        cur = ""
    if cur:
        out.append(cur)
    return out


def fresh_copy(dest: Path) -> Path:
    """The repository's tracked files (what a clone has) copied to ``dest``, with a
    ``.venv`` link to this checkout's environment (as ``make`` would have made it)."""
    listed = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
    ).stdout.decode()
    for rel in filter(None, listed.split("\0")):
        src = ROOT / rel
        if src.is_file():
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)
    (dest / ".venv").symlink_to(ROOT / ".venv", target_is_directory=True)
    return dest


def environment(copy: Path) -> dict[str, str]:
    """The environment commands run in: the copy's code first on the path, headless GL."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(copy)
    env.setdefault("MUJOCO_GL", "egl")
    env.pop("VIRTUAL_ENV", None)
    return env


# ---------------------------------------------------------------------- python
_WORKER = r"""
import ast, builtins, io, json, sys, tokenize, traceback
REPLY = "@@docrun@@"
out = sys.stdout
sys.stdout = sys.stderr  # what blocks print goes to stderr; replies to stdout
real_print = builtins.print

def expected_prints(code):
    comments = {}
    for tok in tokenize.generate_tokens(io.StringIO(code).readline):
        if tok.type == tokenize.COMMENT:
            comments[tok.start[0]] = tok.string[1:].strip()
    want = {}
    for node in ast.walk(ast.parse(code)):
        call = getattr(node, "value", None) if isinstance(node, ast.Expr) else None
        if isinstance(call, ast.Call) and getattr(call.func, "id", "") == "print":
            if node.lineno == node.end_lineno and node.lineno in comments:
                try:
                    want[node.lineno] = str(ast.literal_eval(comments[node.lineno]))
                except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
                    pass
    return want

for request in sys.stdin:
    req = json.loads(request)
    name, code = req["name"], req["code"]
    printed = {}

    def fake_print(*args, **kw):
        frame = sys._getframe(1)
        if frame.f_code.co_filename == name and "file" not in kw:
            buf = io.StringIO()
            real_print(*args, file=buf, **kw)
            printed.setdefault(frame.f_lineno, []).append(buf.getvalue().rstrip("\n"))
        real_print(*args, **kw)

    reply = {"ok": True, "error": ""}
    builtins.print = fake_print
    try:
        want = expected_prints(code)
        exec(compile(code, name, "exec"), {"__name__": "__main__"})
        for line, value in sorted(want.items()):
            got = printed.get(line)
            if not got or any(g != value for g in got):
                reply = {"ok": False, "error": f"line {line}: printed {got!r}, the comment says {value!r}"}
                break
    except BaseException:
        reply = {"ok": False, "error": traceback.format_exc()}
    finally:
        builtins.print = real_print
        sys.stderr.flush()
    out.write(REPLY + json.dumps(reply) + "\n")
    out.flush()
"""


class PythonWorker:
    """One interpreter (the project's, in the copy) that runs blocks one after another."""

    def __init__(self, copy: Path, log: Path) -> None:
        self.log = log.open("w")
        self.proc = subprocess.Popen(
            [sys.executable, "-u", "-c", _WORKER],
            cwd=copy,
            env=environment(copy),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.log,
            text=True,
        )

    def run(self, block: Block) -> str:
        """Run ``block``; "" when it ran as documented, else what went wrong."""
        assert self.proc.stdin is not None
        assert self.proc.stdout is not None
        self.proc.stdin.write(json.dumps({"name": block.where, "code": block.text}) + "\n")
        self.proc.stdin.flush()
        for line in self.proc.stdout:
            if line.startswith("@@docrun@@"):
                reply = json.loads(line[len("@@docrun@@") :])
                return "" if reply["ok"] else reply["error"]
        return f"the interpreter stopped (exit status {self.proc.wait()})"

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)
        self.log.close()


# ---------------------------------------------------------------------- output
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_FREE = re.compile(r"wall (?:time|clock) [-+.\deE]+")  # a stopwatch: differs every run


def same_text(printed: str, documented: str, rel: float = 1e-4, abs_: float = 1e-4) -> bool:
    """Whether printed output matches the documented output: the same words, the same
    numbers within ``rel`` or ``abs_`` (a document shows 4 to 6 digits), wall-clock
    readings free."""
    a, b = _FREE.sub("wall time", printed), _FREE.sub("wall time", documented)
    if _NUMBER.sub("#", a) != _NUMBER.sub("#", b):
        return False
    return all(
        math.isclose(float(x), float(y), rel_tol=rel, abs_tol=abs_)
        for x, y in zip(_NUMBER.findall(a), _NUMBER.findall(b), strict=True)
    )


# ---------------------------------------------------------------------- shell
def shell(copy: Path, command: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run one documented command in bash with the environment activated, in ``copy``."""
    if command.startswith("make ") and command.split()[1:2] != ["test"]:
        # the copy shares this checkout's .venv: take it as installed (never reinstall it)
        command = command.replace("make ", "make -o .venv/.installed ", 1)
    script = f"set -eo pipefail\nsource .venv/bin/activate\n{command}\n"
    return subprocess.run(
        ["bash", "-c", script],
        cwd=copy,
        env=environment(copy),
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def replay_transcript(copy: Path, block: Block) -> str:
    """Feed a transcript's typed lines to ``workcell shell --echo``; "" when the output is
    the transcript, else the difference."""
    typed = [ln[len(PROMPT) :] for ln in block.text.splitlines() if ln.startswith(PROMPT)]
    run = subprocess.run(
        [sys.executable, "-m", "workcell.cli", "shell", "--echo"],
        cwd=copy,
        env=environment(copy),
        input="\n".join(typed) + "\n",
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=300,
    )
    if same_text(run.stdout.strip(), block.text.strip()):
        return ""
    import difflib

    diff = difflib.unified_diff(
        block.text.strip().splitlines(),
        run.stdout.strip().splitlines(),
        "documented",
        "printed",
        lineterm="",
    )
    return "\n".join(diff)
