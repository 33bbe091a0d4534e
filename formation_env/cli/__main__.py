"""``python -m formation_env.cli`` == ``formation-env``."""

import sys

from . import main

sys.exit(main())
