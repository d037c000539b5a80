"""Help texts that list the SOURCE and SINK kinds, read from the one kinds table (:mod:`hapmotion.live.kinds`)
when ``--help`` is asked for, so listing the commands does not load the live package."""

from __future__ import annotations

import click

SOURCES = "{SOURCE KINDS}"
SINKS = "{SINK KINDS}"
"""Placeholders in a command's help text for the table's lines."""


class KindsHelpCommand(click.Command):
    """A click command whose help text has :data:`SOURCES` / :data:`SINKS` filled from the kinds table."""

    def format_help_text(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        if self.help and (SOURCES in self.help or SINKS in self.help):
            from ..live.kinds import SINK_HELP, SOURCE_HELP  # the live package, only when help is shown

            self.help = self.help.replace(SOURCES, SOURCE_HELP.rstrip("\n")).replace(SINKS, SINK_HELP.rstrip("\n"))
        super().format_help_text(ctx, formatter)
