"""docs/protocol.md and docs/program.md describe what the code does."""

from __future__ import annotations

from pathlib import Path

from workcell.program import COMMANDS
from workcell.program.keytree import leaves
from workcell.program.language import TREE
from workcell.program.protocol import DEFAULT_PORT, MAX_MESSAGE_BYTES, VERSION

DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_the_protocol_document_lists_every_command_and_states_the_bound():
    text = (DOCS / "protocol.md").read_text()
    assert f"version {VERSION}" in text
    assert f"{MAX_MESSAGE_BYTES:,} bytes" in text
    assert f"127.0.0.1:{DEFAULT_PORT}" in text
    listed = {line.split("`")[1] for line in text.splitlines() if line.startswith("| `")}
    assert set(COMMANDS) <= listed, set(COMMANDS) - listed


def test_the_language_reference_lists_every_command():
    text = (DOCS / "program.md").read_text()
    for _, leaf in leaves(TREE):
        if leaf.syntax:
            assert leaf.syntax.replace("|", "\\|") in text, leaf.syntax
    assert "workcell> " in text  # the transcript
