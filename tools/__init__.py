"""Reference generators and figure tools (not shipped): run them by path from the repository root,
``.venv/bin/python tools/<name>.py``; tests import them as ``from tools import <name>``."""
