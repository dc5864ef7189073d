"""`python -m mocap.cli`: the `mocap` command."""

import sys

from mocap.cli.main import main

sys.exit(main())
