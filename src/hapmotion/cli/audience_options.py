"""The audience's security options, shared by ``hapmotion live`` (the ``nats://`` sink) and ``hapmotion listen``:
NATS credentials and TLS, the venue's signing key (live) or public key (listen), or ``--unsigned``.

Secrets never go on a command line: options name files (a password file, a token file, an NKey seed, a ``.creds``
file, the keys) and the environment holds the rest (``HAPMOTION_NATS_PASSWORD``, ``HAPMOTION_NATS_TOKEN``;
:mod:`hapmotion.audience.connection`).
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Optional

import click

FILE = click.Path(dir_okay=False)

_NATS = [
    click.option("--nats-user", metavar="NAME", envvar="HAPMOTION_NATS_USER", default=None,
                 help="NATS user name; the password comes from --nats-password-file or HAPMOTION_NATS_PASSWORD "
                      "[env HAPMOTION_NATS_USER]."),
    click.option("--nats-password-file", metavar="FILE", type=FILE, default=None,
                 help="A file holding the NATS password (or the environment variable HAPMOTION_NATS_PASSWORD)."),
    click.option("--nats-token-file", metavar="FILE", type=FILE, default=None,
                 help="A file holding a NATS token (or the environment variable HAPMOTION_NATS_TOKEN)."),
    click.option("--nats-nkey", metavar="FILE", type=FILE, default=None,
                 help="A NATS NKey seed file (hapmotion venue-setup writes venue.nk and seat.nk) "
                      "[env HAPMOTION_NATS_NKEY]."),
    click.option("--nats-creds", metavar="FILE", type=FILE, default=None,
                 help="A NATS JWT .creds file (accounts run by an operator) [env HAPMOTION_NATS_CREDS]."),
    click.option("--nats-ca", metavar="FILE", type=FILE, default=None,
                 help="TLS: the CA certificate(s) the server's certificate is checked against (PEM); implies TLS."),
    click.option("--nats-cert", metavar="FILE", type=FILE, default=None,
                 help="TLS: this client's certificate (PEM), with --nats-key, for servers that verify clients."),
    click.option("--nats-key", metavar="FILE", type=FILE, default=None, help="TLS: the key of --nats-cert (PEM)."),
    click.option("--nats-tls-name", metavar="NAME", default=None,
                 help="TLS: the name the server's certificate must carry (default: the URL's host)."),
    click.option("--unsigned", is_flag=True,
                 help="A rehearsal without keys: nothing is signed or checked, and the start-up line says so."),
]


def _auth(values: dict[str, Any]):
    from ..audience.connection import NatsAuth

    return NatsAuth.from_env(user=values.pop("nats_user"), password_file=values.pop("nats_password_file"),
                             token_file=values.pop("nats_token_file"), nkey=values.pop("nats_nkey"),
                             creds=values.pop("nats_creds"), ca=values.pop("nats_ca"), cert=values.pop("nats_cert"),
                             key=values.pop("nats_key"), tls_name=values.pop("nats_tls_name"))


def _apply(options: list, command: Callable) -> Callable:
    for option in reversed(options):
        command = option(command)
    return command


def publisher_security_options(command: Callable) -> Callable:
    """``hapmotion live``: the options above and ``--venue-key FILE``; every ``nats://`` sink of the command is
    built with them (:func:`hapmotion.audience.publishing`). The command's own parameters are unchanged."""
    @functools.wraps(command)
    def run(**kwargs: Any) -> Any:
        from ..audience.publisher import PublisherSecurity, publishing
        from ..audience.signing import load_private_key

        key_file: Optional[str] = kwargs.pop("venue_key")
        unsigned: bool = kwargs.pop("unsigned")
        auth = _auth(kwargs)
        if key_file is not None and unsigned:
            raise click.UsageError("--venue-key and --unsigned exclude each other")
        key = load_private_key(key_file) if key_file is not None else None
        with publishing(PublisherSecurity(auth=auth, key=key, unsigned=unsigned)):
            return command(**kwargs)

    venue_key = click.option("--venue-key", metavar="FILE", type=FILE, envvar="HAPMOTION_VENUE_KEY", default=None,
                             help="nats:// sink: the venue's Ed25519 private key (PEM) that signs the show "
                                  "[env HAPMOTION_VENUE_KEY].")
    return _apply([venue_key, *_NATS], run)


def seat_security_options(command: Callable) -> Callable:
    """``hapmotion listen``: the options above and ``--venue-pubkey FILE``, given to the command as
    ``security`` (:class:`hapmotion.audience.SeatSecurity`)."""
    @functools.wraps(command)
    def run(**kwargs: Any) -> Any:
        from ..audience.listener import SeatSecurity
        from ..audience.signing import load_public_key

        key_file: Optional[str] = kwargs.pop("venue_pubkey")
        unsigned: bool = kwargs.pop("unsigned")
        auth = _auth(kwargs)
        if key_file is not None and unsigned:
            raise click.UsageError("--venue-pubkey and --unsigned exclude each other")
        key = load_public_key(key_file) if key_file is not None else None
        if key is None and not unsigned:
            raise click.UsageError("a seat checks the venue's signature: give --venue-pubkey FILE (or "
                                   "HAPMOTION_VENUE_PUBKEY), or --unsigned for a rehearsal without keys")
        return command(security=SeatSecurity(auth=auth, venue_key=key, unsigned=unsigned), **kwargs)

    pubkey = click.option("--venue-pubkey", metavar="FILE", type=FILE, envvar="HAPMOTION_VENUE_PUBKEY",
                          default=None, help="The venue's Ed25519 public key (PEM): only what it signed plays "
                                             "[env HAPMOTION_VENUE_PUBKEY].")
    return _apply([pubkey, *_NATS], run)


def _list_audio_inputs(ctx: click.Context, _param: click.Parameter, value: bool) -> None:
    """``--list-audio-inputs``: print the capture devices (or why there are none) and the file/pipe inputs, exit."""
    if not value or ctx.resilient_parsing:
        return
    from ..audio.inputs import SPECS, list_inputs

    listing = list_inputs()
    click.echo("audio inputs for --sync audio (--audio-input SPEC):")
    for spec, what in listing.devices:
        click.echo(f"  {spec:40s} {what}")
    if listing.problem:
        click.echo(f"  (no devices: {listing.problem})")
    click.echo("  file:PATH / wav:PATH|- / raw:PATH|-?rate=48000&channels=2&format=s16   an audio file, a WAV or raw "
               "PCM stream (a pipe or standard input)")
    click.echo(f"forms: {SPECS}")
    ctx.exit(0)


def seat_sync_options(command: Callable) -> Callable:
    """``hapmotion listen``: ``--sync audio`` and its settings, given to the command as ``sync``
    (:class:`hapmotion.audience.seat_sync.SyncSettings` or None); ``--list-audio-inputs`` prints and exits."""
    @functools.wraps(command)
    def run(**kwargs: Any) -> Any:
        mode = kwargs.pop("sync_mode")
        spec, unsynced, max_delay_ms = kwargs.pop("audio_input"), kwargs.pop("unsynced"), kwargs.pop("sync_max_delay")
        sync = None
        if mode == "audio":
            from ..audience.seat_sync import SyncSettings

            sync = SyncSettings(input=spec or "loopback", unsynced=unsynced or "delay",
                                max_delay_s=max_delay_ms / 1000.0)
        else:
            given = click.get_current_context().get_parameter_source("sync_max_delay")
            if spec is not None or unsynced is not None or given is not click.core.ParameterSource.DEFAULT:
                raise click.UsageError("--audio-input, --unsynced and --sync-max-delay need --sync audio")
        return command(sync=sync, **kwargs)

    options = [
        click.option("--sync", "sync_mode", type=click.Choice(["off", "audio"]), default="off", show_default=True,
                     help="audio: play in step with the music this computer plays (or hears), matched against the "
                          "venue's reference; --delay is then a fine offset on top."),
        click.option("--audio-input", metavar="SPEC", default=None,
                     help="What --sync audio listens to: loopback (the default output's loopback/monitor; the "
                          "default), mic, device:NAME, file:PATH, wav:PATH|-, "
                          "raw:PATH|-?rate=R&channels=C&format=s16|f32 (raw without them: 48000 Hz, 2 channels, "
                          "s16) (--list-audio-inputs)."),
        click.option("--unsynced", type=click.Choice(["delay", "silent"]), default=None,
                     help="While --sync audio is not locked: play at the manual --delay (delay, the default) or "
                          "not at all (silent)."),
        click.option("--sync-max-delay", metavar="MS", type=float, default=10000.0, show_default=True,
                     help="--sync audio searches delays behind the venue up to this many milliseconds "
                          "(1000..60000)."),
        click.option("--list-audio-inputs", is_flag=True, expose_value=False, is_eager=True,
                     callback=_list_audio_inputs, help="List the audio inputs --sync audio can use, and exit."),
    ]

    return _apply(options, run)
