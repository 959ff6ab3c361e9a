"""The flag forms of ``scanlines eval`` (``--real LOG``, ``--map LOG``, ...) as its subcommands."""

from __future__ import annotations

import shlex
import sys

import typer.core

#: Each mode flag of the old form, the subcommand it names, whether it takes a value.
MODE_FLAGS: dict[str, tuple[str, bool]] = {
    "--real": ("real", True),
    "--labels": ("labels", True),
    "--map": ("map", True),
    "--trajectory": ("trajectory", True),
    "--family": ("family", False),
}
#: What a command with no mode flag and no subcommand runs.
DEFAULT_SUBCOMMAND = "sim"
HELP_FLAGS = ("--help", "-h")


def subcommand_args(args: list[str]) -> tuple[list[str], bool]:
    """``args`` of ``scanlines eval`` as a subcommand's, and whether they were of the old
    form: the mode flag's values become the subcommand's arguments (``--real A --real B
    --scans 9`` is ``real A B --scans 9``), no mode flag is ``sim``, no argument is ``sim``."""
    if not args:
        return [DEFAULT_SUBCOMMAND], False
    if not args[0].startswith("-") or args[0] in HELP_FLAGS:
        return list(args), False
    modes: list[str] = []
    values: list[str] = []
    rest: list[str] = []
    tokens = iter(args)
    for token in tokens:
        flag, equals, value = token.partition("=")
        if flag not in MODE_FLAGS:
            rest.append(token)
            continue
        mode, takes_value = MODE_FLAGS[flag]
        modes.append(mode)
        if takes_value:
            given = value if equals else next(tokens, None)
            if given is not None:
                values.append(given)
    kinds = list(dict.fromkeys(modes))
    if len(kinds) > 1:
        from scanlines.errors import ParameterError

        flags = ", ".join(f"--{kind}" for kind in kinds)
        raise ParameterError(f"{flags}: one kind of evaluation at a time (scanlines eval --help)")
    return [kinds[0] if kinds else DEFAULT_SUBCOMMAND, *values, *rest], True


class EvalGroup(typer.core.TyperGroup):
    """``scanlines eval``: its subcommands, and the old flag forms run as them with one
    line on stderr naming the new form; bare ``scanlines eval`` is ``scanlines eval sim``."""

    def parse_args(self, ctx, args: list[str]) -> list[str]:
        from scanlines.errors import ParameterError

        try:
            new, old_form = subcommand_args(args)
        except ParameterError as error:
            print(f"scanlines: error: {error}", file=sys.stderr)
            raise typer.Exit(2) from None
        if old_form:
            print(
                f"scanlines: note: this is now `scanlines eval {shlex.join(new)}`",
                file=sys.stderr,
            )
        return super().parse_args(ctx, new)
