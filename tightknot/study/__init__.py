"""One knot studied end to end: tied, measured, summarised, logged, drawn."""
