"""``--token`` and ``--token-file`` of ``hapmotion live``: the shared secret of a ``ws://`` source, from a file, the
environment (``HAPMOTION_LIVE_TOKEN``) or, least safely, the command line.

A command line is readable by every local user (``ps``, ``/proc/PID/cmdline``), so a secret given there is warned
about when the source starts (:class:`~hapmotion.live.ws_source.WsSource`); a file (read once at start, first line, surrounding blanks stripped) or the environment keeps it out of
the process list.
"""

from __future__ import annotations

import os
import stat
from typing import Any, Callable, Optional

import click

from ..errors import UsageError

TOKEN_ENV = "HAPMOTION_LIVE_TOKEN"
MAX_TOKEN_FILE_BYTES = 4096
"""A token file holds one secret: anything larger is not one."""


def read_token_file(path: str) -> str:
    """The secret in ``path``: its first line without surrounding blanks; UsageError when it cannot be read, is
    larger than :data:`MAX_TOKEN_FILE_BYTES` or holds no secret. A file other users may read is warned about."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            raise UsageError(f"--token-file {path}: expected a file")
        if info.st_size > MAX_TOKEN_FILE_BYTES:
            raise UsageError(f"--token-file {path}: expected one secret, found a file of {info.st_size} bytes")
        with open(path, encoding="utf-8") as fh:
            first = fh.readline(MAX_TOKEN_FILE_BYTES).strip()
    except OSError as exc:
        raise UsageError(f"--token-file {path}: cannot read it ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise UsageError(f"--token-file {path}: expected the secret as UTF-8 text") from None
    if not first:
        raise UsageError(f"--token-file {path}: expected a secret on its first line, found none")
    if info.st_mode & (stat.S_IRGRP | stat.S_IROTH):
        # (logging is not set up while options are read: straight to stderr, as the session's lines look)
        click.echo(f"live: --token-file {path} can be read by other users of this machine (chmod 600 it)", err=True)
    return first


def _read_file(ctx: click.Context, param: click.Parameter, value: Optional[str]) -> None:
    if value is not None:
        ctx.meta["hapmotion.token_file"] = read_token_file(value)


def _token(ctx: click.Context, param: click.Parameter, value: Optional[str]) -> Optional[str]:
    from_file = ctx.meta.get("hapmotion.token_file")
    if from_file is not None:
        if value is not None:
            raise UsageError(f"give the token once: --token-file, or --token / {TOKEN_ENV}")
        return from_file
    return value


def token_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """``--token SECRET`` (or ``HAPMOTION_LIVE_TOKEN``) and ``--token-file FILE``, given to the command as ``token``."""
    command = click.option(
        "--token-file", metavar="FILE", default=None, is_eager=True, expose_value=False, callback=_read_file,
        help="Read the --token secret from the first line of FILE (keep it chmod 600).")(command)
    return click.option(
        "--token", envvar=TOKEN_ENV, default=None, metavar="SECRET", callback=_token,
        help="ws:// source: senders must present this secret, as 'Authorization: Bearer SECRET' or ?token=SECRET in "
             f"the URL [env {TOKEN_ENV}]. On the command line every local user can read it: prefer --token-file or "
             "the environment.")(command)
