"""``python -m posture_id.cli``."""

import sys

from posture_id.cli import main

sys.exit(main())
