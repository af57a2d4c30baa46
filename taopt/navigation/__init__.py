"""Minimum-time navigation in a drift field (thesis §2.3, §3.3)."""
