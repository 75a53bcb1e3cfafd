"""Reversal theory of the seed paper (reversal) and zero crossings of sampled profiles (crossings)."""
