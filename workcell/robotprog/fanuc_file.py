"""FANUC LS files (the layout :mod:`workcell.robotprog.read_fanuc` reads): the sections,
the ``/MN`` lines as the tokens of each statement (numbered lines, ``:`` continuation
lines, remarks left out) and the ``/POS`` positions.
"""

from __future__ import annotations

import re

from workcell.robotprog.fanuc_run import Position
from workcell.robotprog.source import NUMBER, Loc, Token, error, tokenize

__all__ = ["RULES", "positions", "ref", "sections", "statements"]

RULES = [
    ("_ws", r"[ \t\r\f]+"),
    ("ref2", r"\[\s*\d+\s*,\s*\d+\s*\]"),
    ("ref", r"\[\s*\d+\s*(?::[^\]\n]*)?\]"),
    ("num", NUMBER),
    ("str", r"'[^'\n]*'|\"[^\"\n]*\""),
    ("unit", r"mm/sec|cm/min|inch/min|deg/sec|msec|sec"),
    ("id", r"[A-Za-z_$][A-Za-z0-9_$.]*"),
    ("op", r"<>|<=|>=|[-+*/()\[\],:=<>%!]"),
]
_MN = re.compile(r"^\s*(\d+)\s*:(.*)$")
_CONT = re.compile(r"^\s*:(.*)$")
_FIELD = re.compile(r"([XYZWPR]|J\d)\s*=\s*([-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?)")


def ref(t: Token) -> tuple[int, str]:
    """(number, comment) of a reference token ``[n]`` or ``[n:comment]``."""
    inner = t.text[1:-1]
    n, _, comment = inner.partition(":")
    return int(n.strip()), comment.strip().strip('"')


def positions(lines: list[tuple[int, str]], path: str) -> dict[int, Position]:
    """The /POS section's positions by number (``lines``: the section's (line number,
    text))."""
    out: dict[int, Position] = {}
    text = "\n".join(s for _, s in lines)
    for m in re.finditer(r"P\[(\d+)(?::[^\]]*)?\]\s*\{(.*?)\};", text, re.S):
        n = int(m.group(1))
        body = m.group(2)
        line = lines[text[: m.start()].count("\n")][0]
        loc = Loc(path, line, 1)
        if "GP2" in body:
            raise error(loc, "positions of several motion groups are not supported")
        if n in out:
            raise error(loc, f"P[{n}] is defined twice in /POS (each position once)")
        pos = Position()
        uf = re.search(r"UF\s*:\s*(\d+)", body)
        ut = re.search(r"UT\s*:\s*(\d+)", body)
        pos["uf"] = int(uf.group(1)) if uf else 0
        pos["ut"] = int(ut.group(1)) if ut else 0
        conf = re.search(r"CONFIG\s*:\s*'([^']*)'", body)
        for k, v in _FIELD.findall(body):
            pos[k] = float(v)
        if conf:
            parts = [s.strip() for s in conf.group(1).split(",")]
            flags = " ".join(parts[0].split())
            if not re.fullmatch(r"[NF] [UD] [TB]", flags) or len(parts) != 4:
                raise error(loc, f"CONFIG '{conf.group(1)}' is not 'N|F U|D T|B, t4, t5, t6'")
            try:
                pos["config"] = (flags, *(int(x) for x in parts[1:]))
            except ValueError as exc:
                raise error(
                    loc, f"CONFIG '{conf.group(1)}' has a turn number that is not whole"
                ) from exc
        cart = all(k in pos for k in "XYZWPR")
        joint = "J1" in pos
        if cart == joint:
            raise error(loc, f"P[{n}] must have X, Y, Z, W, P, R or J1 ... J6")
        out[n] = pos
    return out


def sections(text: str, path: str) -> dict[str, list[tuple[int, str]]]:
    """The file's sections (``/PROG``, ``/ATTR``, ``/APPL``, ``/MN``, ``/POS``, ``/END``)
    as their (line number, text); ProgramError for another section, text before
    ``/PROG``, or a file without ``/PROG`` and ``/MN``."""
    out: dict[str, list[tuple[int, str]]] = {}
    current = None
    for i, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if s.startswith("/"):
            current = s.split()[0].upper()
            out.setdefault(current, [])
            if current not in ("/PROG", "/ATTR", "/APPL", "/MN", "/POS", "/END"):
                raise error(Loc(path, i, 1), f"unknown section {current}")
            continue
        if current is None and s:
            raise error(Loc(path, i, 1), "expected /PROG")
        if current is not None:
            out[current].append((i, line))
    if "/PROG" not in out or "/MN" not in out:
        raise error(Loc(path, 1, 1), "an LS program needs /PROG and /MN")
    return out


def statements(lines: list[tuple[int, str]], path: str) -> list[list[Token]]:
    """The tokens of each statement of the /MN section (``lines``: its (line number,
    text)), at their places in the file: a numbered line ``n: ... ;`` and the ``:``
    lines continuing it are one statement; remarks (``!``, ``//``) are left out."""
    out: list[list[Token]] = []
    for i, line in lines:
        if not line.strip():
            continue
        m, c = _MN.match(line), _CONT.match(line)
        if m is None and c is None:
            raise error(Loc(path, i, 1), "expected a numbered line 'n:  ... ;'")
        body = (m or c).group(2 if m else 1)  # type: ignore[union-attr]
        col = line.index(body) + 1
        stripped = body.rstrip()
        if (
            not stripped.endswith(";")
            and m is not None
            and not stripped.lstrip().startswith(("C ", "C\t"))
        ):
            raise error(Loc(path, i, col + len(stripped)), "expected ';' at the end of the line")
        if stripped.endswith(";"):
            stripped = stripped[:-1]
        if stripped.lstrip().startswith("!") or stripped.lstrip().startswith("//"):
            continue
        toks = tokenize(" " * (col - 1) + stripped, path, RULES)[:-1]
        toks = [Token(t.kind, t.text, Loc(path, i, t.loc.col)) for t in toks]
        if c is not None:
            if not out:
                raise error(Loc(path, i, 1), "a continuation line without a statement")
            out[-1].extend(toks)
        elif toks:
            out.append(toks)
    return out
