"""``hapmotion venue-setup``: a venue's keys and nats-server configuration, with per-subject permissions
(docs/audience.md, "Deploying a show")."""

from __future__ import annotations

from typing import Optional

import click

HELP = """Write a venue's keys and a nats-server configuration into a new FOLDER (nothing is overwritten).

\b
FOLDER/venue.key          the venue's Ed25519 signing key: hapmotion live --venue-key (keep it at the venue)
FOLDER/venue.pub          its public key: hand it to every seat (hapmotion listen --venue-pubkey)
FOLDER/venue.nk           the publisher's NATS NKey seed: hapmotion live --nats-nkey (keep it at the venue)
FOLDER/seat.nk            the seats' NATS NKey seed: hand it to every seat (hapmotion listen --nats-nkey)
FOLDER/nats-server.conf   nats-server -c FOLDER/nats-server.conf: JetStream, TLS (with --tls-cert/--tls-key) and
                          the permissions: the venue publishes the show and its description, seats only
                          subscribe and read the description; every file in it by its absolute path, so
                          it runs from any directory
\b
Example:
  hapmotion venue-setup venue --show concert --tls-cert server.pem --tls-key server-key.pem
"""


@click.command("venue-setup", help=HELP)
@click.argument("folder", type=click.Path(file_okay=False))
@click.option("--show", "show", default="*", show_default=True, metavar="SHOW",
              help="The show the permissions are for (* = every show on this server).")
@click.option("--host", default="0.0.0.0", show_default=True,
              help="The address the server listens on (0.0.0.0: every interface, for seats on other machines; "
                   "127.0.0.1 for a rehearsal on this machine only).")
@click.option("--port", type=int, default=4222, show_default=True, help="The port the server listens on.")
@click.option("--tls-cert", metavar="FILE", default=None, help="The server's TLS certificate (PEM); with --tls-key.")
@click.option("--tls-key", metavar="FILE", default=None, help="The key of --tls-cert (PEM).")
@click.option("--tls-ca", metavar="FILE", default=None,
              help="CA of client certificates the server verifies (optional).")
@click.option("--store-dir", metavar="DIR", default=None,
              help="JetStream's folder on the server (default: FOLDER/jetstream).")
def command(folder: str, show: str, host: str, port: int, tls_cert: Optional[str], tls_key: Optional[str],
            tls_ca: Optional[str], store_dir: Optional[str]) -> None:
    from ..audience.venue_config import write_venue

    paths = write_venue(folder, show=show, host=host, port=port, tls_cert=tls_cert, tls_key=tls_key, tls_ca=tls_ca,
                        store_dir=store_dir)
    for name, path in paths.items():
        click.echo(f"venue-setup: {name.replace('_', ' ')}: {path}", err=True)
    if tls_cert is None:
        click.echo("venue-setup: no --tls-cert: the server speaks plain NATS (credentials and show in the clear); "
                   "use TLS beyond a closed network", err=True)
