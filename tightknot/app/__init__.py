"""The command line and what it writes: run folders, configs, progress, the demo."""
