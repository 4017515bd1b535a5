"""The exercises domain: models, schemas, service and router."""
