"""The auth domain: models, schemas, service and router."""
