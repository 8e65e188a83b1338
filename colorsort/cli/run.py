"""How every console script ends on an error: one message line on stderr and ``colorsort.errors.exit_code``'s status.

``prog: error: MESSAGE`` for bad input (status 2: nothing was done, nothing overwritten), ``prog: MESSAGE`` for
work that failed (status 1), ``prog: interrupted`` for Ctrl-C (130; ``prog: interrupted: N of M episodes kept in
...`` where a run kept what it finished). argparse's own usage errors stay argparse's.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from typing import Protocol

from colorsort.errors import INTERRUPTED, USAGE, ColorSortError, Interrupted, exit_code


class Main(Protocol):
    """A console script's entry point: its arguments (None: ``sys.argv[1:]``) -> exit status."""

    def __call__(self, argv: list[str] | None = None) -> int: ...


def guarded(prog: str) -> Callable[[Main], Main]:
    """Decorate a console script's ``main(argv) -> status``: the errors ColorSort raises become an exit status."""

    def wrap(main: Main) -> Main:
        @functools.wraps(main)
        def run(argv: list[str] | None = None) -> int:
            try:
                return main(argv)
            except Interrupted as stop:  # a run that kept what it finished says so
                print(f"{prog}: {stop}", file=sys.stderr)
                return INTERRUPTED
            except KeyboardInterrupt:
                print(f"{prog}: interrupted", file=sys.stderr)
                return INTERRUPTED
            except (ColorSortError, ValueError, FileExistsError, RuntimeError) as err:
                code = exit_code(err)
                print(f"{prog}: {'error: ' if code == USAGE else ''}{err}", file=sys.stderr)
                return code

        return run

    return wrap
