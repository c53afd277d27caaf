"""docs/program.md's motion transcript is what the shell prints for those lines."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

DOC = Path(__file__).resolve().parents[2] / "docs" / "program.md"


def test_the_motion_transcript_is_what_the_shell_prints():
    text = DOC.read_text()
    section = text[text.index("## Motion like an industrial controller") :]
    start = section.index("```\nworkcell> ") + len("```\n")
    block = section[start : section.index("```", start)]
    lines = [ln[len("workcell> ") :] for ln in block.splitlines() if ln.startswith("workcell> ")]
    run = subprocess.run(
        [sys.executable, "-m", "workcell.cli", "shell", "--echo"],
        input="\n".join(lines) + "\n",
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=300,
    )
    assert run.stdout.strip() == block.strip()
