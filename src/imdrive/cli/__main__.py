"""``python -m imdrive.cli``: the ``imdrive`` command."""

from imdrive.cli import main

raise SystemExit(main())
