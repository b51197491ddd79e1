"""``python -m cistrack.cli``: the same as the installed ``cistrack`` command."""
from cistrack.cli.main import console_main

console_main()
