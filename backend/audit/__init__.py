"""The audit domain: models, schemas, service and router."""
