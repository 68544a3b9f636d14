"""Load paths: tying, tightening and pulling knots, one rod or a batch."""
