"""`tune`: parameters for an identified machine, their margins and the tracking they predict."""
