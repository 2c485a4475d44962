"""`identify BAG`: a machine's axes identified from a recorded run (docs/bring-up.md)."""
