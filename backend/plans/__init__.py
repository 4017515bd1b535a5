"""The plans domain: models, schemas, service and router."""
