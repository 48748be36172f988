"""Every subcommand's ``--help`` states exit status 3 (an unexpected error, a fault of
startrack's) and the variable that shows its traceback, as ``startrack --help`` and the README do:
in each of its exit-status texts, in the one sentence :mod:`startrack.cli._common` holds."""

from __future__ import annotations

import re

import pytest

from startrack.cli import SUBCOMMANDS, main
from startrack.cli._common import FAULT_EXIT_STATUS, HELP_WIDTH
from startrack.cli._main import DEBUG_ENV, INTERNAL_ERROR

CAMPAIGN_ACTIONS = ("run", "report", "rerun", "list")
HELP_ARGS = [[command] for command in SUBCOMMANDS] + [["campaign", action] for action in CAMPAIGN_ACTIONS]
"""Every subcommand, and each action of ``campaign``."""


def _help(command: list[str], capsys) -> str:
    """The printed ``startrack COMMAND --help`` (argparse's SystemExit(0) is the exit status)."""
    code = main([*command, "--help"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


def _exit_status_texts(text: str) -> list[str]:
    """Each part of ``text`` from an "exit status" (any case) to the end of its paragraph."""
    return [text[m.start():].split("\n\n")[0] for m in re.finditer("exit status", text, re.IGNORECASE)]


@pytest.mark.parametrize("command", HELP_ARGS, ids=" ".join)
def test_every_exit_status_text_of_the_help_states_status_3(command, capsys):
    texts = _exit_status_texts(_help(command, capsys))
    assert texts, f"startrack {command} --help has no exit status"
    for text in texts:
        flat = " ".join(text.split())
        assert re.search(rf"[\s;,:]{INTERNAL_ERROR} an unexpected error\b", flat), text
        assert f"{DEBUG_ENV}=1" in flat, text


@pytest.mark.parametrize("command", HELP_ARGS, ids=" ".join)
def test_the_help_states_status_3_with_the_shared_sentence(command, capsys):
    """The sentence of :mod:`startrack.cli._common`, wrapped within the epilogs' width."""
    texts = _exit_status_texts(_help(command, capsys))
    for text in texts:
        assert FAULT_EXIT_STATUS in " ".join(text.split()), text
        assert max(len(line) for line in text.splitlines()) <= HELP_WIDTH, text
