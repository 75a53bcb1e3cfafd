"""Analytic references (analytic), their fallback within limits (fallback), the reference type (trajectory)."""
