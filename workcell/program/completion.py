"""Tab completion of the command language for prompt_toolkit (imported by the shell only).

Offers the keywords valid at the cursor and the names the session knows there
(entities, relations of the owner typed, robots, parts), each replacing the word being
typed; see :func:`workcell.program.language.complete`.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from prompt_toolkit.completion import Completer, Completion

from workcell.program.language import complete
from workcell.program.session import Session

__all__ = ["WorkcellCompleter"]


class WorkcellCompleter(Completer):
    """Completes the language for ``session`` (its names as they are at each keystroke)."""

    def __init__(self, session: Session) -> None:
        self.session = session

    def get_completions(self, document: Any, complete_event: Any) -> Iterator[Completion]:
        """Completions for the text before the cursor."""
        words, n = complete(document.text_before_cursor, self.session)
        for w in words:
            yield Completion(w, start_position=-n)
