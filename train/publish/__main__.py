"""``python -m train.publish RUN_DIR NAME [...]``: :func:`train.publish.publish.main`."""

from .publish import main

raise SystemExit(main())
