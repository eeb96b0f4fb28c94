"""``python -m eos_svc.cli`` = the ``eos`` command."""

import sys

from eos_svc.cli import main

sys.exit(main())
