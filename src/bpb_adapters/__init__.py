"""Built-in model adapters: the offline baselines and the litellm provider adapter."""
