"""Chapter 5: precedence-constrained truck–drone delivery."""
