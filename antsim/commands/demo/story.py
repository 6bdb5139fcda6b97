"""How the walk-through is told: chapters of paragraphs, figures, tables and commands to try,
printed as they are told and collected for ``demo.html``."""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from dataclasses import dataclass, field

from controller.errors import InputError

__all__ = ["Chapter", "Story", "edit_scenario"]


@dataclass
class Chapter:
    """One step of the story: a title and its report blocks (paragraphs, figures, tables,
    commands), in order."""

    title: str
    blocks: list = field(default_factory=list)


class Story:
    """Collects chapters for demo.html and prints their text as it is told. ``commands``:
    every "try it yourself" command, in the order told (``demo.json`` keeps them)."""

    def __init__(self, echo: Callable[[str], None],
                 on_chapter: Callable[[str], None] | None = None):
        self.echo = echo
        self.on_chapter = on_chapter
        self.chapters: list[Chapter] = []
        self.commands: list[str] = []

    def chapter(self, title: str) -> Chapter:
        if self.on_chapter is not None:
            self.on_chapter(title)
        self.chapters.append(Chapter(title))
        self.echo("")
        self.echo(title)
        self.echo("=" * len(title))
        return self.chapters[-1]

    def say(self, chapter: Chapter, text: str) -> None:
        from antsim.figures.html import Paragraph

        chapter.blocks.append(Paragraph(text))
        self.echo(textwrap.fill(text, width=92))
        self.echo("")

    def command(self, chapter: Chapter, text: str) -> None:
        """A command line the reader can run to repeat the step (it must run as printed:
        tests/end_to_end/test_demo.py runs every one)."""
        from antsim.figures.html import Preformatted

        chapter.blocks.append(Preformatted(text, caption="Try it yourself"))
        self.commands.append(text)
        self.echo("  $ " + text)
        self.echo("")

    def figure(self, chapter: Chapter, figure) -> None:
        """A figure the demo drew (an :class:`antsim.figures.style.FigureFile`)."""
        from antsim.figures.html import Figure

        chapter.blocks.append(Figure.of(figure))
        self.echo(f"  [figure: {figure.path}]")

    def page_figure(self, chapter: Chapter, path, title: str, caption: str) -> None:
        """A figure an ``antsim run`` report drew (a PNG file), with the demo's own words."""
        from antsim.figures.html import Figure

        chapter.blocks.append(Figure(path, title, caption))
        self.echo(f"  [figure: {path}]")

    def table(self, chapter: Chapter, table) -> None:
        chapter.blocks.append(table)


def edit_scenario(text: str, old: str, new: str, where: str) -> str:
    """Scenario ``text`` with ``old`` (which must occur exactly once) replaced by ``new``."""
    if text.count(old) != 1:
        raise InputError(where, "scenario text", old,
                         f"occurs {text.count(old)} times (the demo expects it once)",
                         "use the ghigo1990 scenario that comes with antsim")
    return text.replace(old, new)
