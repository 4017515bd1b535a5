"""The S3 store: any S3-compatible service (MinIO, AWS S3, Ceph RGW …) through boto3."""

from __future__ import annotations

import base64
import binascii
import io
from collections.abc import Callable, Iterator
from typing import IO, Any

from backend.storage.base import CHUNK, ObjectStore, is_object_key
from backend.storage.errors import StorageError, StoredObjectMissing

_MISSING = ("NoSuchKey", "404", "NotFound")


class S3Store(ObjectStore):
    """Objects as bucket/prefix + key; a PUT is atomic in S3 (readers see the old object or the whole new one)."""

    name = "s3"

    def __init__(self, client: Any, bucket: str, prefix: str = "", endpoint: str = "") -> None:
        self.client = client
        self.bucket = bucket
        self.prefix = prefix.strip("/") + "/" if prefix.strip("/") else ""
        self.endpoint = endpoint

    @classmethod
    def connect(
        cls,
        *,
        bucket: str,
        prefix: str = "",
        endpoint_url: str = "",
        region: str = "us-east-1",
        access_key_id: str = "",
        secret_access_key: str = "",
    ) -> S3Store:
        """Returns a store on `bucket` (credentials: the given keys, else boto3's usual chain)."""
        import boto3
        from botocore.config import Config

        client = boto3.client(
            "s3",
            endpoint_url=endpoint_url or None,
            region_name=region,
            aws_access_key_id=access_key_id or None,
            aws_secret_access_key=secret_access_key or None,
            config=Config(retries={"max_attempts": 5, "mode": "standard"}, s3={"addressing_style": "path"}),
        )
        return cls(client, bucket, prefix, endpoint_url or "AWS")

    def _name(self, key: str) -> str:
        if not is_object_key(key):
            raise StorageError(f"invalid object key {key!r}")
        return self.prefix + key

    def _call(self, what: str, key: str, fn: Callable[..., Any], **kw: Any) -> Any:
        from botocore.exceptions import BotoCoreError, ClientError

        try:
            return fn(Bucket=self.bucket, **kw)
        except ClientError as exc:
            code = str(exc.response.get("Error", {}).get("Code", ""))
            if code in _MISSING:
                raise StoredObjectMissing(f"stored object {key} is missing from bucket {self.bucket}") from None
            raise StorageError(f"cannot {what} {key} in bucket {self.bucket}: {code} {exc}") from None
        except BotoCoreError as exc:
            raise StorageError(f"cannot {what} {key} in bucket {self.bucket} at {self.endpoint}: {exc}") from None

    def _put_file(self, key: str, file: IO[bytes], sha256: str, size: int) -> None:
        name = self._name(key)
        try:
            head = self._call("check", key, self.client.head_object, Key=name)
            if head.get("Metadata", {}).get("sha256") == sha256 and head.get("ContentLength") == size:
                return  # already there: content-addressed
        except StoredObjectMissing:
            pass
        checksum = base64.b64encode(binascii.unhexlify(sha256)).decode()
        # one PUT, its body streamed from the file (botocore sends a file object in chunks), checked by S3 against
        # the sha256: a reader sees the old object or the whole new one
        self._call("write", key, self.client.put_object, Key=name, Body=file, ContentLength=size,
                   ChecksumSHA256=checksum, Metadata={"sha256": sha256})  # fmt: skip

    def _get(self, key: str) -> bytes:
        body = self._call("read", key, self.client.get_object, Key=self._name(key))["Body"]
        try:
            return body.read()
        finally:
            body.close()

    def _open(self, key: str) -> IO[bytes]:
        body = self._call("read", key, self.client.get_object, Key=self._name(key))["Body"]
        return io.BufferedReader(_Body(body, f"cannot read {key} from bucket {self.bucket} at {self.endpoint}"), CHUNK)

    def exists(self, key: str) -> bool:
        """Returns whether key is in the bucket."""
        try:
            self._call("check", key, self.client.head_object, Key=self._name(key))
        except StoredObjectMissing:
            return False
        return True

    def delete(self, key: str) -> None:
        """Removes key (nothing happens when it is absent)."""
        self._call("delete", key, self.client.delete_object, Key=self._name(key))

    def keys(self) -> Iterator[str]:
        """Yields every object key under the prefix."""
        pages = self.client.get_paginator("list_objects_v2").paginate(Bucket=self.bucket, Prefix=self.prefix)
        for page in pages:
            for item in page.get("Contents", []):
                key = item["Key"][len(self.prefix) :]
                if is_object_key(key):
                    yield key

    def ensure_bucket(self) -> None:
        """Creates the bucket when it does not exist."""
        from botocore.exceptions import ClientError

        try:
            self.client.head_bucket(Bucket=self.bucket)
        except ClientError:
            self._call("create bucket for", self.bucket, self.client.create_bucket)

    def describe(self) -> str:
        """Returns the bucket, prefix and endpoint."""
        return f"S3 bucket {self.bucket}{'/' + self.prefix if self.prefix else ''} at {self.endpoint}"


class _Body(io.RawIOBase):
    """A GET's streaming body as a readable binary file whose read errors (a dropped connection, a timeout) are
    StorageError."""

    def __init__(self, body: Any, said: str) -> None:
        super().__init__()
        self._body, self._said = body, said

    def readable(self) -> bool:
        """Returns True: the body is read, never written."""
        return True

    def readinto(self, buffer: Any) -> int:
        """Reads up to len(buffer) bytes into buffer; returns how many (0 at the end)."""
        from botocore.exceptions import BotoCoreError
        from urllib3.exceptions import HTTPError

        try:
            data = self._body.read(len(buffer))
        except (BotoCoreError, HTTPError, OSError) as exc:
            raise StorageError(f"{self._said}: {exc}") from None
        buffer[: len(data)] = data
        return len(data)

    def close(self) -> None:
        """Closes the body (its connection goes back to the pool, or is dropped when not read to its end)."""
        if not self.closed:
            self._body.close()
        super().close()
