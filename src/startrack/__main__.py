"""``python -m startrack``: the command line, as the ``startrack`` console script runs it."""

from .cli import main

raise SystemExit(main())
