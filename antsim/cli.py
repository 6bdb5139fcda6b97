"""The ``antsim`` command line: one console script with a subcommand per job.

Every subcommand lives in :mod:`antsim.commands` as a module with ``configure(parser)`` and
``main(args) -> int``; modules are imported only when their subcommand runs, so ``--help``
stays fast. ``antsim help COMMAND`` is ``antsim COMMAND --help``. Bad input of any kind ends
with one line on stderr and exit status 2; a misspelt command or option is answered with the
one meant ("did you mean --model?").
"""

from __future__ import annotations

import argparse
import difflib
import errno
import gc
import importlib
import io
import os
import re
import sys
import warnings
from pathlib import PurePath

from controller.errors import InputError, Note
from controller.pointing.legacy import RelabelledTermsWarning

from ._version import __version__

#: subcommand -> (module, one-line help)
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "run": ("antsim.commands.run", "simulate a pointing campaign, reduce, fit and report"),
    "fit": ("antsim.commands.fit", "fit a pointing model to recordings or a TPOINT data file"),
    "diagnose": ("antsim.commands.diagnose", "find the physics a pointing model misses"),
    "plan": ("antsim.commands.plan", "answer what-if questions about an observing plan"),
    "blindtest": ("antsim.commands.blindtest", "score diagnose on recordings with hidden effects"),
    "demo": ("antsim.commands.demo", "teaching walk-through: cold start to closed loop"),
    "serve": ("antsim.commands.serve", "the simulated antenna as a KATCP device, for "
              "closed-loop tests of control software"),
    "scenarios": ("antsim.commands.scenarios", "list the scenarios and plans that come with "
                  "antsim (run them by name)"),
}

EXIT_INPUT = 2


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line and exit status 2, naming the
    option and the value as every bad input's line does (argparse's own words where its
    message has another shape)."""

    def error(self, message: str):  # type: ignore[override]
        parts = _usage_parts(message)
        if parts is None:
            self.exit(EXIT_INPUT, f"{self.prog}: error: {message} (see {self.prog} --help)\n")
        field, value, problem = parts
        line = InputError("command line", field, value, problem, f"see {self.prog} --help")
        self.exit(EXIT_INPUT, f"{self.prog}: error: {line.line()}\n")


#: argparse's usage errors: "argument OPTION: invalid int value: 'x'" and the like
_INVALID = re.compile(r"argument (?P<option>[^:]+): invalid (?P<kind>\w+) value: (?P<value>.*)")
_EXPECTED = re.compile(r"argument (?P<option>[^:]+): expected (?P<what>.+)")
_REQUIRED = re.compile(r"the following arguments are required: (?P<names>.+)")
_KINDS = {"int": "must be an integer", "float": "must be a number"}


def _usage_parts(message: str) -> tuple[str, str, str] | None:
    """(option, value, problem) of an argparse usage error (None: another shape)."""
    if match := _INVALID.fullmatch(message):
        option = match["option"].split("/")[0]
        value = match["value"].strip("'")
        return option, value, _KINDS.get(match["kind"], f"not a valid {match['kind']} value")
    if match := _EXPECTED.fullmatch(message):
        return match["option"].split("/")[0], "<missing>", f"expected {match['what']}"
    if match := _REQUIRED.fullmatch(message):
        return match["names"].split(", ")[0], "<missing>", "required"
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (all of them when None)."""
    parser = OneLineParser(
        prog="antsim",
        description="Simulate a radio telescope being pointed, and calibrate its pointing.",
        epilog="antsim help COMMAND (or antsim COMMAND --help) prints a command's options.",
    )
    parser.add_argument("--version", action="version", version=f"antsim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    parser.commands = {}
    for name, (module_name, help_text) in SUBCOMMANDS.items():
        sp = sub.add_parser(name, help=help_text, description=help_text)
        if command is None or name == command:
            importlib.import_module(module_name).configure(sp)
        sp.set_defaults(_module=module_name)
        parser.commands[name] = sp
    return parser


def os_error_line(err: OSError) -> str:
    """One line for a file-system error: the file, what the system said, and its code."""
    network = isinstance(err, ConnectionError | TimeoutError)
    filename = err.filename if err.filename is not None or network else _file_of(err)
    where = filename if filename is not None else "network" if network else "system"
    code = errno.errorcode.get(err.errno or 0, "")
    text = f"{where}: {err.strerror or type(err).__name__}" + (f" [{code}]" if code else "")
    if err.filename2 is not None:
        text += f" (with {err.filename2})"
    return " ".join(text.split()) + "; files written before it are kept"


def _file_of(err: OSError) -> str | None:
    """The file a failed write was writing, where the error does not name it (ENOSPC from
    ``write`` knows only a descriptor): the path or open file of the innermost frame that
    holds one (``Path.write_text``'s own path, a writer's file object). antsim's own
    outputs name their file (:func:`antsim.outdir.write_file`); this names the others'."""
    frames = []
    tb = err.__traceback__
    while tb is not None:
        frames.append(tb.tb_frame)
        tb = tb.tb_next
    for frame in reversed(frames):
        for value in frame.f_locals.values():
            if isinstance(value, PurePath):
                return str(value)
            if isinstance(value, io.IOBase) and isinstance(getattr(value, "name", None), str):
                return value.name
    return None


def _suggestion(word: str, known) -> str:
    """"did you mean X?" for the ``known`` word closest to ``word`` ("" for none close)."""
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=0.6)
    return f"did you mean {close[0]}?" if close else ""


def _usage_error(command: str | None, field: str, value: str, problem: str,
                 hint: str) -> int:
    where = f"antsim {command}" if command else "antsim"
    err = InputError("command line", field, value, problem,
                     hint or f"see {where} --help")
    print(f"{where}: error: {err.line()}", file=sys.stderr)
    return EXIT_INPUT


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["help"]:  # antsim help [COMMAND]: the command's --help
        argv = [*argv[1:2], "--help"]
    command = next((a for a in argv if not a.startswith("-")), None)
    if command is not None and command not in SUBCOMMANDS:
        return _usage_error(None, "COMMAND", command, "not a command of antsim",
                            _suggestion(command, [*SUBCOMMANDS, "help"]))
    parser = build_parser(command)
    try:
        args, extra = parser.parse_known_args(argv)
    except SystemExit as done:  # a usage error's line is printed; --help exits as it does
        if done.code == EXIT_INPUT:
            return EXIT_INPUT
        raise
    if not getattr(args, "command", None):
        parser.print_help()
        return EXIT_INPUT
    if extra:  # a misspelt option, or an argument too many
        options = [o for a in parser.commands[args.command]._actions for o in a.option_strings]
        word = extra[0]
        if word.startswith("-"):
            return _usage_error(args.command, "option", word.split("=")[0],
                                f"not an option of antsim {args.command}",
                                _suggestion(word.split("=")[0], options))
        return _usage_error(args.command, "argument", word,
                            f"not expected by antsim {args.command}", "")
    module = importlib.import_module(args._module)
    _replace_unencodable(sys.stdout)
    try:
        if args.command in DRAWS:
            check_figure_backend()
        with warnings.catch_warnings():
            warnings.simplefilter("always", RelabelledTermsWarning)
            warnings.simplefilter("always", Note)
            warnings.showwarning = _notes_in_one_line(args.command, warnings.showwarning)
            code = int(module.main(args) or 0)
            sys.stdout.flush()  # here, where a reader that left is caught, not at exit
            return code
    except InputError as err:
        print(f"antsim {args.command}: error: {err.line()}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:  # the reader left (`antsim diagnose --list | head`): not an error
        _silence_stdout()
        return EXIT_BROKEN_PIPE
    except OSError as err:  # the file system said no: a full disk, a lost permission, ...
        print(f"antsim {args.command}: error: {os_error_line(err)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"antsim {args.command}: interrupted; recordings written so far are kept",
              file=sys.stderr)
        return 130


#: the commands that draw figures (with matplotlib, which reads MPLBACKEND when imported)
DRAWS = frozenset({"run", "diagnose", "plan", "demo"})


def check_figure_backend() -> None:
    """A matplotlib backend named by ``MPLBACKEND`` that matplotlib refuses is one line,
    before anything runs (matplotlib's import raises on it, after the campaign; antsim
    draws on its own Agg canvases whatever the variable names)."""
    import os

    name = os.environ.get("MPLBACKEND")
    if not name:
        return
    # matplotlib's first import validates the variable and, refusing it, leaves half its
    # modules imported: it is imported without the variable, which is then checked alone
    del os.environ["MPLBACKEND"]
    try:
        from matplotlib import rcsetup
    finally:
        os.environ["MPLBACKEND"] = name
    try:
        rcsetup.validate_backend(name)
    except ValueError:
        raise InputError("environment", "MPLBACKEND", name, "is not a matplotlib backend",
                         "unset it (antsim draws with Agg whatever it names) or name one, "
                         "e.g. agg") from None


def _replace_unencodable(stream) -> None:
    """Text the stream's encoding cannot hold (a scenario named in Greek on an ASCII
    terminal, PYTHONIOENCODING=ascii) is written as backslash escapes, not a
    UnicodeEncodeError after every file was written (stderr does so already)."""
    reconfigure = getattr(stream, "reconfigure", None)
    if reconfigure is not None and getattr(stream, "errors", None) == "strict":
        reconfigure(errors="backslashreplace")


EXIT_BROKEN_PIPE = 141
"""A shell's status for a process ended by SIGPIPE (128 + 13), which Python ignores."""


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's flush at exit does not
    fail on the closed pipe a second time (Python's signal docs, "Note on SIGPIPE")."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def _notes_in_one_line(command: str, show):
    """A ``warnings.showwarning`` printing notes to the user (a file's W terms renamed, see
    :mod:`controller.pointing.legacy`; a :class:`~controller.errors.Note`, such as a damaged
    cache rebuilt) as one line, ``antsim COMMAND: note: ...``; other warnings go to
    ``show``. A note is printed once, however often the file is read."""
    printed: set[str] = set()

    def showwarning(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, RelabelledTermsWarning | Note):
            if str(message) not in printed:
                printed.add(str(message))
                print(f"antsim {command}: note: {message}", file=sys.stderr)
        else:
            show(message, category, filename, lineno, file, line)
    return showwarning


def command() -> int:
    """The ``antsim`` console script and ``python -m antsim``: :func:`main`, then no
    garbage collection while the interpreter shuts down. Its last collections walk every
    object the command made (astropy's and scipy's modules, the recordings) to free memory
    the process is about to return anyway: 0.1 s of the ``antsim run`` command. Objects are
    still freed as their last reference goes, and exit handlers run as usual."""
    code = main()
    gc.disable()
    gc.freeze()
    return code


if __name__ == "__main__":
    raise SystemExit(command())
