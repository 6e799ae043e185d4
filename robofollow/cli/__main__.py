"""`python -m robofollow.cli`."""

import sys

from robofollow.cli import main

sys.exit(main())
