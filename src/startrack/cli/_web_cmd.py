"""startrack web: the browser tool, a local server with pages and a JSON API (docs/web.md).

Open the address it prints. Jobs run in worker processes; their results stay under --data-dir,
so a restart lists them again. The server binds to 127.0.0.1 (this computer only) unless --host
says otherwise; it has no accounts, so think before exposing it to a network."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import InvalidInputError
from ..web import (
    DEFAULT_MAX_QUEUED,
    DEFAULT_MAX_UPLOAD_MB,
    DEFAULT_PORT,
    DEFAULT_TIME_LIMIT_S,
    WebConfig,
    default_data_dir,
)
from ._common import exit_status_epilog
from ._parser import CommandParser

EPILOG = exit_status_epilog(
    "0 the server stopped normally (Ctrl-C); 2 misuse (a bad option, a --root that is not a folder, a port in use), "
    "with one line 'startrack web: error: ...' on standard error;")


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack web", description=__doc__, epilog=EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this computer only)")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT,
                        help=f"port (default {DEFAULT_PORT}; 0: any free one)")
    parser.add_argument("--max-upload-mb", type=float, default=DEFAULT_MAX_UPLOAD_MB,
                        help=f"largest upload, MB (default {DEFAULT_MAX_UPLOAD_MB:g})")
    parser.add_argument("--data-dir", type=Path, help=f"where jobs are kept (default {default_data_dir()})")
    parser.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--root", type=Path, help="a folder whose sub-folders may be solved as result sets")
    parser.add_argument("--time-limit-s", type=float, default=DEFAULT_TIME_LIMIT_S,
                        help=f"time limit of one job, s (default {DEFAULT_TIME_LIMIT_S:g})")
    parser.add_argument("--max-queued", type=int, default=DEFAULT_MAX_QUEUED,
                        help=f"jobs that may wait for a worker (default {DEFAULT_MAX_QUEUED}); more are refused (429)")
    return parser


def config_from(args: argparse.Namespace) -> WebConfig:
    """The checked server settings of the command line."""
    if not 0 <= args.port <= 65535:
        raise InvalidInputError(f"--port must be within 0..65535, got {args.port}")
    kwargs = {"workers": args.workers, "max_upload_mb": args.max_upload_mb, "root": args.root,
              "time_limit_s": args.time_limit_s, "max_queued": args.max_queued}
    if args.data_dir is not None:
        kwargs["data_dir"] = args.data_dir
    try:
        return WebConfig(**kwargs)
    except InvalidInputError as exc:  # "workers must be ..." -> "--workers must be ..."
        name, _, rest = str(exc).partition(" ")
        raise InvalidInputError(f"--{name.replace('_', '-')} {rest}") from None


def _make_data_dir(folder: Path) -> None:
    """Create the data folder (and its parents) if missing; InvalidInputError naming --data-dir when it
    is a file or cannot be made."""
    if folder.exists() and not folder.is_dir():
        raise InvalidInputError(f"--data-dir {folder} is a file; give a folder (it is created if missing)")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidInputError(f"cannot create --data-dir {folder}: {exc.strerror or exc}") from None


def main(argv: list[str]) -> int:
    """Run the server until interrupted."""
    import socket

    import uvicorn

    from ..web import create_app

    args = _parser().parse_args(argv)
    config = config_from(args)
    _make_data_dir(config.data_dir)
    sock = socket.socket(socket.AF_INET6 if ":" in args.host else socket.AF_INET)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((args.host, args.port))
        sock.listen(2048)  # connections wait in the backlog until the server accepts them
    except OSError as exc:
        raise OSError(f"cannot listen on {args.host}:{args.port}: {exc.strerror}") from None
    host, port = sock.getsockname()[:2]
    print(f"startrack web: http://{'[' + host + ']' if ':' in host else host}:{port}/ "
          f"(data in {config.data_dir}, {config.workers} worker(s)); Ctrl-C stops it", file=sys.stderr, flush=True)
    server = uvicorn.Server(uvicorn.Config(create_app(config), log_level="warning", access_log=False))
    try:
        server.run(sockets=[sock])
    except KeyboardInterrupt:  # uvicorn re-raises the Ctrl-C it handled: for a server, the normal stop
        pass
    print("startrack web: stopped", file=sys.stderr)
    return 0
