"""What a run did: metrics from time series; the model validation."""
